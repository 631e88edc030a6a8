#include "rtt/rtt.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/compress/material_error.h"
#include "prtlab/render/btf_table_material.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/storage/archive.h"
#include "prtlab/transfer/radiance_to_bins.h"

namespace prt::rtt {
namespace {

// The midpoint rule's sub-squares per cell side for B: its error is far below the SH truncation.
constexpr int kCellSubdivisions = 16;

std::vector<double> cell_integrals(int light_side, int order) {
  return sh_cell_integrals(HemisphereGrid(light_side), order, kCellSubdivisions);
}

class RttCompressor final : public MaterialCompressor {
 public:
  explicit RttCompressor(int order) : order_(order) {}
  std::unique_ptr<CompressedMaterial> compress(const MaterialInput& input,
                                               Progress& progress) const override {
    if (!input.btf) throw ParameterError("material rtt: no BTF given");
    auto table = std::make_shared<const Btf>(project_btf(*input.btf, order_));
    RttMaterial probe(sampling_of(*input.btf), table, 0.0);
    // A black BTF projects to exact zeros: no relative error exists, and none is lost.
    const double measured = material_error(probe, *input.btf).relative_l2;
    const double error = std::isnan(measured) ? 0.0 : measured;
    progress.finish();
    return std::make_unique<RttMaterial>(sampling_of(*input.btf), std::move(table), error);
  }

 private:
  int order_;
};

}  // namespace

Btf project_btf(const Btf& btf, int order) {
  if (order < 1 || order > kMaxOrder)
    throw ParameterError(fmt::format("material rtt: order {} is not in 1..{}", order, kMaxOrder));
  const int m = btf.light_count(), n = order * order;
  const std::vector<double> b = cell_integrals(btf.light_side(), order);
  const std::size_t vectors = static_cast<std::size_t>(btf.texel_count()) * btf.view_count();
  std::vector<float> out(vectors * static_cast<std::size_t>(n) * 3);
  tbb::parallel_for(std::size_t{0}, vectors, [&](std::size_t v) {
    const float* in = btf.data().data() + v * static_cast<std::size_t>(m) * 3;
    float* dst = out.data() + v * static_cast<std::size_t>(n) * 3;
    for (int i = 0; i < n; ++i) {
      double acc[3] = {0, 0, 0};
      for (int j = 0; j < m; ++j) {
        const double w = b[static_cast<std::size_t>(j) * n + i];
        for (int c = 0; c < 3; ++c) acc[c] += w * in[j * 3 + c];
      }
      for (int c = 0; c < 3; ++c) dst[i * 3 + c] = static_cast<float>(acc[c]);
    }
  });
  nlohmann::json params = {{"source", btf.parameters()}, {"order", order}};
  return Btf(btf.material(), btf.resolution(), btf.view_side(), order, std::move(out),
             std::move(params));
}

RttMaterial::RttMaterial(MaterialSampling sampling, std::shared_ptr<const Btf> table, double error)
    : sampling_(std::move(sampling)), table_(std::move(table)), error_(error) {
  if (!table_) throw ParameterError("material rtt: no table given");
  PRT_CHECK(
      table_->resolution() == sampling_.resolution && table_->view_side() == sampling_.view_side,
      "material rtt: the table's texels and views differ from the sampling's");
  cells_ = cell_integrals(sampling_.light_side, table_->light_side());
  const double omega = HemisphereGrid(sampling_.light_side).cell_solid_angle();
  for (double& v : cells_) v /= omega;
}

StorageReport RttMaterial::storage() const {
  const std::uint64_t n = static_cast<std::uint64_t>(table_->light_count());
  const std::uint64_t views = table_->view_independent() ? 1 : table_->view_count();
  const std::uint64_t bytes = static_cast<std::uint64_t>(table_->texel_count()) * views * n * 3 * 4;
  return {{{"rtt", bytes,
            table_->view_independent()
                ? fmt::format("f32 RGB x {} SH coefficients per texel (view independent: one "
                              "vector a texel)",
                              n)
                : fmt::format("f32 RGB x {} SH coefficients per texel and view sample, "
                              "rgb[((texel * V + view) * n + i) * 3 + channel]",
                              n)}}};
}

double RttMaterial::flops_per_pixel() const {
  const double n = table_->light_count();
  const double samples = table_->view_independent() ? 1.0 : 4.0;
  return 2.0 * samples * n + 2.0 * n;
}

Rgb RttMaterial::reflectance(int texel, int view, int light) const {
  const int n = table_->light_count();
  const std::span<const float> v = table_->light_vector(texel, view);
  const double* w = cells_.data() + static_cast<std::size_t>(light) * n;
  double acc[3] = {0, 0, 0};
  for (int i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) acc[c] += w[i] * v[static_cast<std::size_t>(i) * 3 + c];
  return Rgb(static_cast<float>(acc[0]), static_cast<float>(acc[1]), static_cast<float>(acc[2]));
}

void RttMaterial::eval_lights(Vec2 uv, Vec3 view_local, std::span<Rgb> out,
                              TexelFilter filter) const {
  table_->eval_lights(uv, view_local, out, filter);
}

Rgb RttMaterial::shade(Vec2 uv, Vec3 view_local, std::span<const Rgb> light,
                       TexelFilter filter) const {
  return table_->shade(uv, view_local, light, filter);
}

std::unique_ptr<DeviceMaterial> RttMaterial::upload(
    ClContext& context, std::span<const CompressedMaterial* const> parts,
    const ParamSet& /*device_options*/) const {
  std::vector<const Btf*> tables;
  for (const CompressedMaterial* p : parts) {
    const auto* r = dynamic_cast<const RttMaterial*>(p);
    if (!r)
      throw ParameterError(fmt::format("material rtt: a part's material is '{}', not rtt",
                                       p ? p->backend() : std::string("(none)")));
    tables.push_back(&r->table());
  }
  return upload_btf_tables(context, tables, std::string(kName));
}

void RttMaterial::save(ArchiveWriter& w) const {
  const Btf& t = *table_;
  w.add_meta(std::string(kName), {{"format_version", kStateVersion},
                                  {"material", t.material()},
                                  {"resolution", t.resolution()},
                                  {"view_side", t.view_side()},
                                  {"light_side", sampling_.light_side},
                                  {"order", t.light_side()},
                                  {"view_independent", t.view_independent()},
                                  {"error", error_},
                                  {"parameters", t.parameters()}});
  if (!t.view_independent()) {
    w.add_section("rtt", std::vector<float>(t.data().begin(), t.data().end()));
    return;
  }
  std::vector<float> one_view;
  for (int texel = 0; texel < t.texel_count(); ++texel) {
    const auto v = t.light_vector(texel, 0);
    one_view.insert(one_view.end(), v.begin(), v.end());
  }
  w.add_section("rtt", std::move(one_view));
}

std::unique_ptr<CompressedMaterial> RttMaterial::load(const ArchiveReader& r) {
  const auto meta = r.meta_value<nlohmann::json>(std::string(kName));
  const auto fail = [&](const std::string& problem) {
    return InputError(r.path(), fmt::format("material rtt: {}", problem));
  };
  try {
    const int version = meta.at("format_version").get<int>();
    if (version != kStateVersion)
      throw fail(fmt::format("state version {} is not {}", version, kStateVersion));
    const int res = meta.at("resolution").get<int>();
    const int views = meta.at("view_side").get<int>();
    const int lights = meta.at("light_side").get<int>();
    const int order = meta.at("order").get<int>();
    const bool independent = meta.at("view_independent").get<bool>();
    const double error = meta.at("error").get<double>();
    if (res < 1 || res > 4096 || views < 1 || views > 64 || lights < 1 || lights > 64 ||
        order < 1 || order > kMaxOrder)
      throw fail(fmt::format("resolution {}, view side {}, light side {}, order {} out of range",
                             res, views, lights, order));
    if (!(std::isfinite(error) && error >= 0)) throw fail("the stored error is not finite");
    const std::uint64_t vector = static_cast<std::uint64_t>(order) * order * 3;
    const std::uint64_t texels = static_cast<std::uint64_t>(res) * res;
    const std::uint64_t view_count = static_cast<std::uint64_t>(views) * views;
    std::vector<float> stored =
        r.section<float>("rtt", texels * (independent ? 1 : view_count) * vector);
    if (!std::all_of(stored.begin(), stored.end(), [](float v) { return std::isfinite(v); }))
      throw fail("a texture value is not finite");
    std::vector<float> all;
    if (independent) {
      all.reserve(texels * view_count * vector);
      for (std::uint64_t t = 0; t < texels; ++t)
        for (std::uint64_t v = 0; v < view_count; ++v)
          all.insert(all.end(), stored.begin() + static_cast<std::ptrdiff_t>(t * vector),
                     stored.begin() + static_cast<std::ptrdiff_t>((t + 1) * vector));
    } else {
      all = std::move(stored);
    }
    auto table = std::make_shared<const Btf>(meta.at("material").get<std::string>(), res, views,
                                             order, std::move(all), meta.at("parameters"));
    if (table->view_independent() != independent)
      throw fail("the texture's view dependence differs from its metadata");
    MaterialSampling s{meta.at("material").get<std::string>(), res, views, lights};
    return std::make_unique<RttMaterial>(std::move(s), std::move(table), error);
  } catch (const nlohmann::json::exception& e) {
    throw fail(fmt::format("bad metadata ({})", e.what()));
  }
}

MaterialEntry registry_entry() {
  MaterialEntry e;
  e.name = std::string(kName);
  e.description =
      "radiance transfer texture (Sloan et al. 2004): the BTF's light side projected onto SH "
      "per texel and view sample; shades SH local radiance with one dot product";
  e.params = {{"order",
               ParamType::kInt,
               "5",
               1.0,
               static_cast<double>(kMaxOrder),
               {},
               "SH order of the light side (n = order^2 coefficients; the paper: 5, n = 25); "
               "must equal the transfer backend's order"}};
  e.lossless = false;
  e.create = [](const ParamSet& p) -> std::unique_ptr<MaterialCompressor> {
    return std::make_unique<RttCompressor>(static_cast<int>(p.get_int("order")));
  };
  e.load = &RttMaterial::load;
  return e;
}

PRT_REGISTER_MATERIAL(registry_entry);

}  // namespace prt::rtt
