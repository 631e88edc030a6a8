#include "full/full.h"

#include <fmt/format.h>

#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/storage/archive.h"

namespace prt::full {
namespace {

class FullCompressor final : public MaterialCompressor {
 public:
  std::unique_ptr<CompressedMaterial> compress(const MaterialInput& input,
                                               Progress& progress) const override {
    auto out = std::make_unique<FullMaterial>(input.btf);
    progress.finish();
    return out;
  }
};

}  // namespace

FullMaterial::FullMaterial(std::shared_ptr<const Btf> btf) : btf_(std::move(btf)) {
  if (!btf_) throw ParameterError("material full: no BTF given");
}

StorageReport FullMaterial::storage() const {
  return {{{"rgb", btf_->bytes(),
            "f32 per value, rgb[((texel * V + view) * M + light) * 3 + channel]"}}};
}

double FullMaterial::flops_per_pixel() const {
  // b(u, e, .) is a weighted sum of the view samples' vectors (one when the BTF is view
  // independent): a multiply-add per sample and light, then the dot product with L*.
  const double m = btf_->light_count();
  const double samples = btf_->view_independent() ? 1.0 : 4.0;
  return 2.0 * samples * m + 2.0 * m;
}

Rgb FullMaterial::reflectance(int texel, int view, int light) const {
  return btf_->value(texel, view, light);
}

void FullMaterial::eval_lights(Vec2 uv, Vec3 view_local, std::span<Rgb> out,
                               TexelFilter filter) const {
  btf_->eval_lights(uv, view_local, out, filter);
}

Rgb FullMaterial::shade(Vec2 uv, Vec3 view_local, std::span<const Rgb> light,
                        TexelFilter filter) const {
  return btf_->shade(uv, view_local, light, filter);
}

std::unique_ptr<DeviceMaterial> FullMaterial::upload(
    ClContext& context, std::span<const CompressedMaterial* const> parts,
    const ParamSet& /*device_options*/) const {
  std::vector<const FullMaterial*> full;
  for (const CompressedMaterial* p : parts) {
    const auto* f = dynamic_cast<const FullMaterial*>(p);
    if (!f)
      throw ParameterError(fmt::format("material full: a part's material is '{}', not full",
                                       p ? p->backend() : std::string("(none)")));
    full.push_back(f);
  }
  return upload_full(context, full);
}

void FullMaterial::save(ArchiveWriter& w) const {
  w.add_meta(std::string(kName), {{"format_version", kStateVersion},
                                  {"material", btf_->material()},
                                  {"resolution", btf_->resolution()},
                                  {"view_side", btf_->view_side()},
                                  {"light_side", btf_->light_side()},
                                  {"parameters", btf_->parameters()}});
  w.add_section("rgb", btf_->data());
}

std::unique_ptr<CompressedMaterial> FullMaterial::load(const ArchiveReader& r) {
  const auto meta = r.meta_value<nlohmann::json>(std::string(kName));
  try {
    const int version = meta.at("format_version").get<int>();
    if (version != kStateVersion)
      throw InputError(r.path(), fmt::format("material full: state version {} is not {}", version,
                                             kStateVersion));
    const int res = meta.at("resolution").get<int>();
    const int views = meta.at("view_side").get<int>();
    const int lights = meta.at("light_side").get<int>();
    if (res < 1 || res > 4096 || views < 1 || views > 64 || lights < 1 || lights > 64)
      throw InputError(r.path(),
                       fmt::format("material full: resolution {}, view side {}, light side {} "
                                   "out of range",
                                   res, views, lights));
    const std::uint64_t count =
        static_cast<std::uint64_t>(res) * res * views * views * lights * lights * 3;
    auto btf =
        std::make_shared<const Btf>(meta.at("material").get<std::string>(), res, views, lights,
                                    r.section<float>("rgb", count), meta.at("parameters"));
    return std::make_unique<FullMaterial>(std::move(btf));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(r.path(), fmt::format("material full: bad metadata ({})", e.what()));
  }
}

MaterialEntry registry_entry() {
  MaterialEntry e;
  e.name = std::string(kName);
  e.description =
      "the sampled BTF itself (f32 RGB per texel, view and light bin): the lossless reference";
  e.lossless = true;
  e.create = [](const ParamSet&) { return std::make_unique<FullCompressor>(); };
  e.load = &FullMaterial::load;
  return e;
}

PRT_REGISTER_MATERIAL(registry_entry);

}  // namespace prt::full
