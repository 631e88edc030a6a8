#include "coo/coo.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "prtlab/base/error.h"
#include "prtlab/storage/archive.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt::coo {
namespace {

class CooCompressor final : public Compressor {
 public:
  explicit CooCompressor(double keep) : keep_(keep) {}

  std::unique_ptr<CompressedTransfer> compress(const TransferInput& input,
                                               Progress& progress) const override {
    check_transfer_shape(input, kName);
    const TransferMatrix& t = input.transfer;
    Triplets out;
    out.vertices = t.vertex_count();
    out.local_count = t.local_count();
    out.pixel_count = static_cast<int>(t.cols());
    out.rows.reserve(t.nnz());
    const auto offsets = t.row_offsets();
    double dropped_sq = 0, norm_sq = 0;
    std::vector<std::uint32_t> order;
    for (std::size_t row = 0; row < t.rows(); ++row) {
      const std::uint32_t begin = offsets[row], end = offsets[row + 1];
      order.resize(end - begin);
      for (std::uint32_t i = begin; i < end; ++i) order[i - begin] = i;
      // Largest first, ties by column: deterministic.
      std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
        return t.counts()[a] > t.counts()[b];
      });
      const auto kept =
          static_cast<std::size_t>(std::ceil(keep_ * static_cast<double>(order.size())));
      for (std::size_t q = kept; q < order.size(); ++q)
        dropped_sq += double(t.value(order[q])) * t.value(order[q]);
      order.resize(kept);
      std::sort(order.begin(), order.end());
      for (std::uint32_t i = begin; i < end; ++i) norm_sq += double(t.value(i)) * t.value(i);
      for (std::uint32_t i : order) {
        out.rows.push_back(static_cast<std::uint32_t>(row));
        out.columns.push_back(t.column(i));
        out.values.push_back(t.value(i));
      }
    }
    out.expected_frobenius = norm_sq > 0 ? std::sqrt(dropped_sq / norm_sq) : 0.0;
    progress.finish();
    return std::make_unique<CooTransfer>(std::move(out));
  }

 private:
  double keep_;
};

}  // namespace

bool built_with_its_deps() {
#ifdef PRTLAB_COO_DEPS_APPLIED
  return true;
#else
  return false;
#endif
}

StorageReport CooTransfer::storage() const {
  const std::uint64_t n = t_.values.size();
  return {{{"rows", n * 4, "u32 per entry: row (vertex * M + j), non-decreasing"},
           {"columns", n * 4, "u32 per entry: global pixel k"},
           {"values", n * 4, "f32 per entry: the transfer value c / s^2"}}};
}

void CooTransfer::check_light(const LightCoeffs& light) const {
  check_pixel_light(light, static_cast<std::size_t>(t_.pixel_count), kName);
}

LightCoeffs CooTransfer::project_light(const Cubemap& radiance) const {
  if (radiance.layout.pixel_count() != t_.pixel_count)
    throw ParameterError(fmt::format("{}: the light has N = {}, the transfer N = {}", kName,
                                     radiance.layout.pixel_count(), t_.pixel_count));
  return {"pixel", radiance.light_vector()};
}

void CooTransfer::relight(const LightCoeffs& light, LocalRadiance& out) const {
  check_light(light);
  out = LocalRadiance(RadianceBasis::kPixel, t_.local_count, t_.vertices);
  for (std::size_t i = 0; i < t_.values.size(); ++i) {
    const Rgb& l = light.values[t_.columns[i]];
    Rgb& o = out.values[t_.rows[i]];
    o.x += t_.values[i] * l.x;
    o.y += t_.values[i] * l.y;
    o.z += t_.values[i] * l.z;
  }
}

std::unique_ptr<DeviceRelighter> CooTransfer::upload(ClContext& context, const ParamSet&) const {
  return upload_triplets(context, t_);
}

void CooTransfer::save(ArchiveWriter& w) const {
  w.add_meta("coo_version", kStateVersion);
  w.add_meta("expected_frobenius", t_.expected_frobenius);
  w.add_meta("vertices", t_.vertices);
  w.add_meta("local_count", t_.local_count);
  w.add_meta("pixel_count", t_.pixel_count);
  w.add_section("rows", t_.rows);
  w.add_section("columns", t_.columns);
  w.add_section("values", t_.values);
}

std::unique_ptr<CompressedTransfer> CooTransfer::load(const ArchiveReader& r) {
  if (const int v = r.meta_value<int>("coo_version"); v != kStateVersion)
    throw InputError(r.path(),
                     fmt::format("{} state version {} is not {}", kName, v, kStateVersion));
  Triplets t;
  t.expected_frobenius = r.meta_value<double>("expected_frobenius");
  if (!(t.expected_frobenius >= 0 && t.expected_frobenius <= 1))
    throw InputError(r.path(), "coo: expected_frobenius out of [0, 1]");
  t.vertices = r.meta_value<std::size_t>("vertices");
  t.local_count = r.meta_value<int>("local_count");
  t.pixel_count = r.meta_value<int>("pixel_count");
  t.rows = r.section<std::uint32_t>("rows");
  t.columns = r.section<std::uint32_t>("columns", t.rows.size());
  t.values = r.section<float>("values", t.rows.size());
  const std::uint64_t row_count = static_cast<std::uint64_t>(t.vertices) * t.local_count;
  if (t.local_count < 1 || t.pixel_count < 1) throw InputError(r.path(), "coo: empty bases");
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    if (t.rows[i] >= row_count || t.columns[i] >= static_cast<std::uint32_t>(t.pixel_count) ||
        (i > 0 && t.rows[i] < t.rows[i - 1]))
      throw InputError(r.path(), fmt::format("coo: entry {} is out of range or out of order", i));
  }
  return std::make_unique<CooTransfer>(std::move(t));
}

namespace {
CompressorEntry registry_entry() {
  CompressorEntry e;
  e.name = std::string(kName);
  e.description =
      "test-only: T as sorted (row, column, value) triplets, proving a backend is its folder";
  e.params = {{"keep",
               ParamType::kReal,
               "1",
               0.0,
               1.0,
               {},
               "fraction of each row's entries kept, largest first (1 = lossless)"}};
  e.size_knob = SizeKnob{.key = "keep", .direction = SizeKnob::Direction::kLargerIsMoreStorage};
  e.lossless = true;
  e.create = [](const ParamSet& p) -> std::unique_ptr<Compressor> {
    return std::make_unique<CooCompressor>(p.get_real("keep"));
  };
  e.load = &CooTransfer::load;
  // A made-up published number, so the CLI's paper lines have a backend and scene to match.
  e.published = {{"tiny-sphere-plane",
                  {{"keep", "0.5"}},
                  "half of each row: 1.0 MB (made up)",
                  "tests/backends/coo/coo.cpp"}};
  return e;
}
}  // namespace

PRT_REGISTER_COMPRESSOR(registry_entry);

}  // namespace prt::coo
