#include "haar/haar.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "haar/haar_wavelet.h"
#include "prtlab/base/error.h"
#include "prtlab/numeric/float16.h"
#include "prtlab/storage/archive.h"

namespace prt::haar {
namespace {

enum class IndexWidth { kAuto, kU16, kU32 };

class HaarCompressor final : public Compressor {
 public:
  HaarCompressor(HaarOptions options, IndexWidth index) : o_(options), index_(index) {}

  std::unique_ptr<CompressedTransfer> compress(const TransferInput& input,
                                               Progress& progress) const override {
    check_transfer_shape(input, kName);
    if (!is_power_of_two(input.cubemap.resolution()))
      throw ParameterError(fmt::format(
          "{}: the cubemap resolution R = {} is not a power of two (the 2D Haar transform halves "
          "each face down to one pixel); precompute with a power-of-two resolution",
          kName, input.cubemap.resolution()));
    if (index_ == IndexWidth::kU16 && input.transfer.cols() > 65536)
      throw ParameterError(
          fmt::format("{}: index=u16 cannot address N = {} coefficients (use auto or u32)", kName,
                      input.transfer.cols()));
    HaarOptions o = o_;
    o.wide_index = index_ == IndexWidth::kU32;
    return std::make_unique<HaarTransfer>(encode_haar(input.transfer, input.cubemap, o, progress));
  }

 private:
  HaarOptions o_;
  IndexWidth index_;
};

template <typename E>
E enum_from(std::string_view what, std::string_view name, std::initializer_list<E> all,
            std::string_view (*spell)(E)) {
  for (E e : all)
    if (spell(e) == name) return e;
  throw ParameterError(fmt::format("{}: {} '{}' is unknown", kName, what, name));
}

ValueFormat format_from(std::string_view name) {
  return enum_from<ValueFormat>("value format", name,
                                {ValueFormat::kFloat32, ValueFormat::kFloat16, ValueFormat::kS8},
                                to_string);
}

}  // namespace

bool check_light(const LightCoeffs& light, std::size_t pixels) {
  const bool wavelet = light.basis == kLightBasis;
  if ((!wavelet && light.basis != "pixel") || light.values.size() != pixels)
    throw ParameterError(
        fmt::format("{}: relight needs a light of N = {} values in basis 'pixel' or '{}' (its Haar "
                    "coefficients), got basis '{}' with {}",
                    kName, pixels, kLightBasis, light.basis, light.values.size()));
  return wavelet;
}

std::string_view to_string(ValueFormat f) {
  switch (f) {
    case ValueFormat::kFloat32:
      return "float32";
    case ValueFormat::kFloat16:
      return "float16";
    case ValueFormat::kS8:
      return "s8";
  }
  return "?";
}

std::string_view to_string(Budget b) {
  return b == Budget::kGlobal ? "global" : "row";
}

std::string_view to_string(Scaling s) {
  return s == Scaling::kAlways ? "always" : "ranked";
}

StorageReport HaarTransfer::storage() const {
  const std::uint64_t terms = a_.terms();
  const std::uint64_t rows = a_.rows();
  const std::size_t cb = a_.count_bytes();
  StorageReport r;
  r.components.push_back(
      {"row_counts", rows * cb,
       fmt::format("u{} per row: the row's kept terms (the relight's row offsets are their prefix "
                   "sums, computed at load)",
                   8 * cb)});
  r.components.push_back(
      {"indices", terms * a_.index_bytes(),
       fmt::format("{} per term: the coefficient's index face * R^2 + y * R + x in the Mallat "
                   "layout of haar_wavelet.h, rising within a row",
                   a_.wide ? "u32" : "u16")});
  switch (a_.format) {
    case ValueFormat::kFloat32:
      r.components.push_back({"values", terms * 4, "f32 per term: the Haar coefficient"});
      break;
    case ValueFormat::kFloat16:
      r.components.push_back(
          {"values", terms * 2, "IEEE half per term: the coefficient, round to nearest even"});
      break;
    case ValueFormat::kS8:
      r.components.push_back(
          {"values", terms, "s8 code per term: coefficient = code x the row's scale, -127..127"});
      r.components.push_back({"row_scales", rows * 4,
                              "f32 per row: the largest |coefficient| of the row's terms / 127"});
      break;
  }
  return r;
}

double HaarTransfer::flops_per_relight() const {
  const double scales = a_.format == ValueFormat::kS8 ? static_cast<double>(a_.rows()) : 0.0;
  return transform_flops(a_.resolution) + 2.0 * static_cast<double>(a_.terms()) + scales;
}

LightCoeffs HaarTransfer::project_light(const Cubemap& radiance) const {
  return pixel_light(radiance, static_cast<std::size_t>(a_.pixel_count), kName);
}

LightCoeffs HaarTransfer::project_light(const Cubemap& radiance,
                                        const LightApproximation& approximation) const {
  const LightCoeffs pixels = project_light(radiance);
  return approximate_light(pixels.values, CubemapLayout(a_.resolution), approximation);
}

LightCoeffs HaarTransfer::project_light_under(const Cubemap& radiance,
                                              const ParamSet& light_options) const {
  LightApproximation a;
  a.terms = static_cast<std::size_t>(light_options.get_int("light_terms"));
  a.weight = light_weight_from(light_options.get_string("light_weight"));
  // Every term is the pixel light itself (bit-identical relight): no transform per light.
  if (a.terms == 0 || a.terms >= static_cast<std::size_t>(a_.pixel_count))
    return project_light(radiance);
  return project_light(radiance, a);
}

void HaarTransfer::relight(const LightCoeffs& light, LocalRadiance& out) const {
  const bool wavelet = check_light(light, static_cast<std::size_t>(a_.pixel_count));
  out.ensure_shape(RadianceBasis::kPixel, a_.local_count, a_.vertices);
  if (wavelet) {
    relight_haar_wavelet(a_, light.values, out.values);
  } else {
    relight_haar(a_, light.values, out.values);
  }
}

void HaarTransfer::relight_vertices(const LightCoeffs& light,
                                    std::span<const std::uint32_t> vertices,
                                    LocalRadiance& out) const {
  const bool wavelet = check_light(light, static_cast<std::size_t>(a_.pixel_count));
  check_vertex_subset(vertices, a_.vertices, kName);
  out.ensure_shape(RadianceBasis::kPixel, a_.local_count, a_.vertices);
  if (wavelet) {
    relight_haar_wavelet_vertices(a_, light.values, vertices, out.values);
  } else {
    relight_haar_vertices(a_, light.values, vertices, out.values);
  }
}

std::unique_ptr<DeviceRelighter> HaarTransfer::upload(ClContext& context,
                                                      const ParamSet& device_options) const {
  return upload_haar(
      context, a_,
      device_options.get_enum<DeviceOrder>(
          "opencl_order", {{"rows", DeviceOrder::kRows}, {"columns", DeviceOrder::kColumns}}));
}

void HaarTransfer::save(ArchiveWriter& archive) const {
  archive.add_meta("haar_version", kStateVersion);
  archive.add_meta("vertices", a_.vertices);
  archive.add_meta("local_count", a_.local_count);
  archive.add_meta("pixel_count", a_.pixel_count);
  archive.add_meta("resolution", a_.resolution);
  archive.add_meta("values", std::string(to_string(a_.format)));
  archive.add_meta("budget", std::string(to_string(a_.budget)));
  archive.add_meta("scaling", std::string(to_string(a_.scaling)));
  archive.add_meta("k", a_.k);
  archive.add_meta("wide_indices", a_.wide);
  archive.add_meta("truncation_squared_error", a_.truncation_squared_error);
  archive.add_meta("quantization_squared_error", a_.quantization_squared_error);
  archive.add_meta("total_squared_norm", a_.total_squared_norm);
  const std::size_t cb = a_.count_bytes();
  archive.add_meta("count_bytes", cb);
  std::vector<std::uint32_t> counts(a_.rows());
  for (std::size_t row = 0; row < a_.rows(); ++row) counts[row] = a_.count(row);
  if (cb == 1) {
    archive.add_section("row_counts", std::vector<std::uint8_t>(counts.begin(), counts.end()));
  } else if (cb == 2) {
    archive.add_section("row_counts", std::vector<std::uint16_t>(counts.begin(), counts.end()));
  } else {
    archive.add_section("row_counts", std::move(counts));
  }
  if (a_.wide) {
    archive.add_section("indices", a_.indices32);
  } else {
    archive.add_section("indices", a_.indices16);
  }
  switch (a_.format) {
    case ValueFormat::kFloat32:
      archive.add_section("values", a_.values32);
      break;
    case ValueFormat::kFloat16:
      archive.add_section("values", a_.values16);
      break;
    case ValueFormat::kS8:
      archive.add_section("values", a_.codes);
      archive.add_section("row_scales", a_.row_scales);
      break;
  }
}

std::unique_ptr<CompressedTransfer> HaarTransfer::load(const ArchiveReader& r) {
  const auto fail = [&](const std::string& problem) {
    return InputError(r.path(), fmt::format("{}: {}", kName, problem));
  };
  const int version = r.meta_value<int>("haar_version");
  if (version != kStateVersion)
    throw fail(fmt::format("state version {} is not the version {} this build reads", version,
                           kStateVersion));
  HaarArrays a;
  a.vertices = r.meta_value<std::size_t>("vertices");
  a.local_count = r.meta_value<int>("local_count");
  a.pixel_count = r.meta_value<int>("pixel_count");
  a.resolution = r.meta_value<int>("resolution");
  a.k = r.meta_value<int>("k");
  a.wide = r.meta_value<bool>("wide_indices");
  a.truncation_squared_error = r.meta_value<double>("truncation_squared_error");
  a.quantization_squared_error = r.meta_value<double>("quantization_squared_error");
  a.total_squared_norm = r.meta_value<double>("total_squared_norm");
  try {
    a.format = format_from(r.meta_value<std::string>("values"));
    a.budget = enum_from<Budget>("budget", r.meta_value<std::string>("budget"),
                                 {Budget::kPerRow, Budget::kGlobal}, to_string);
    a.scaling = enum_from<Scaling>("scaling", r.meta_value<std::string>("scaling"),
                                   {Scaling::kRanked, Scaling::kAlways}, to_string);
  } catch (const ParameterError& e) {
    throw fail(e.what());
  }
  if (a.local_count <= 0 || !is_power_of_two(a.resolution) || a.resolution > 8192 ||
      a.pixel_count != 6 * a.resolution * a.resolution)
    throw fail(fmt::format("bad shape: M = {}, R = {}, N = {}", a.local_count, a.resolution,
                           a.pixel_count));
  if (!a.wide && a.pixel_count > 65536)
    throw fail(fmt::format("u16 indices cannot address N = {}", a.pixel_count));
  for (double v : {a.truncation_squared_error, a.quantization_squared_error, a.total_squared_norm})
    if (!(std::isfinite(v) && v >= 0)) throw fail("the error statistics are not finite and >= 0");
  if (a.vertices >
      std::numeric_limits<std::uint32_t>::max() / static_cast<std::uint64_t>(a.local_count))
    throw fail(fmt::format("{} vertices x M = {} rows do not fit the relight's u32 row index",
                           a.vertices, a.local_count));
  const std::uint64_t rows = a.vertices * static_cast<std::uint64_t>(a.local_count);
  const auto cb = r.meta_value<std::size_t>("count_bytes");
  std::vector<std::uint32_t> counts;
  if (cb == 1) {
    const auto c = r.section<std::uint8_t>("row_counts", rows);
    counts.assign(c.begin(), c.end());
  } else if (cb == 2) {
    const auto c = r.section<std::uint16_t>("row_counts", rows);
    counts.assign(c.begin(), c.end());
  } else if (cb == 4) {
    counts = r.section<std::uint32_t>("row_counts", rows);
  } else {
    throw fail(fmt::format("count_bytes = {} is none of 1, 2, 4", cb));
  }
  a.offsets.assign(1, 0);
  a.offsets.reserve(rows + 1);
  for (std::uint32_t c : counts) {
    if (c > static_cast<std::uint32_t>(a.pixel_count))
      throw fail(fmt::format("a row keeps {} terms of N = {}", c, a.pixel_count));
    if (a.offsets.back() > std::numeric_limits<std::uint32_t>::max() - c)
      throw fail("more than 2^32 - 1 terms");
    a.offsets.push_back(a.offsets.back() + c);
  }
  const std::uint64_t terms = a.offsets.back();
  // The kernels trust these arrays: a file that passed the checksum but was written wrong must
  // still not make them read out of bounds.
  const auto check_indices = [&](const auto& indices) {
    for (std::size_t row = 0; row < rows; ++row)
      for (std::uint32_t i = a.offsets[row]; i < a.offsets[row + 1]; ++i) {
        if (indices[i] >= static_cast<std::uint32_t>(a.pixel_count))
          throw fail(fmt::format("an index is out of range (N = {})", a.pixel_count));
        if (i > a.offsets[row] && indices[i] <= indices[i - 1])
          throw fail(fmt::format("the indices of row {} do not rise", row));
      }
  };
  if (a.wide) {
    a.indices32 = r.section<std::uint32_t>("indices", terms);
    check_indices(a.indices32);
  } else {
    a.indices16 = r.section<std::uint16_t>("indices", terms);
    check_indices(a.indices16);
  }
  const auto finite = [](float v) { return std::isfinite(v); };
  switch (a.format) {
    case ValueFormat::kFloat32:
      a.values32 = r.section<float>("values", terms);
      if (!std::all_of(a.values32.begin(), a.values32.end(), finite))
        throw fail("a value is not finite");
      break;
    case ValueFormat::kFloat16:
      a.values16 = r.section<std::uint16_t>("values", terms);
      if (std::any_of(a.values16.begin(), a.values16.end(),
                      [](std::uint16_t h) { return (h & 0x7c00u) == 0x7c00u; }))
        throw fail("a half value is infinite or NaN");
      break;
    case ValueFormat::kS8:
      a.codes = r.section<std::int8_t>("values", terms);
      a.row_scales = r.section<float>("row_scales", rows);
      if (!std::all_of(a.row_scales.begin(), a.row_scales.end(),
                       [](float s) { return std::isfinite(s) && s >= 0; }))
        throw fail("a row scale is not finite and >= 0");
      break;
  }
  return std::make_unique<HaarTransfer>(std::move(a));
}

CompressorEntry registry_entry() {
  CompressorEntry e;
  e.name = std::string(kName);
  e.description =
      "non-linear Haar wavelets (Ng et al. 2003): per row of T the k 2D Haar coefficients (per "
      "cube face) of largest |c| x support solid angle; the light is transformed per relight";
  e.params = {
      {"k",
       ParamType::kInt,
       "12",
       1.0,
       1048576.0,
       {},
       "terms kept per row (budget=row), or the mean per row (budget=global); a row keeps at "
       "most its non-zero coefficients"},
      {"values",
       ParamType::kEnum,
       "s8",
       std::nullopt,
       std::nullopt,
       {"float32", "float16", "s8"},
       "term values: f32, IEEE half (round to nearest even), or s8 codes -127..127 times a "
       "per-row f32 scale max|c|/127 (the paper's 3 bytes a term with u16 indices)"},
      {"index",
       ParamType::kEnum,
       "auto",
       std::nullopt,
       std::nullopt,
       {"auto", "u16", "u32"},
       "term index width: auto = u16 when N <= 65536, else u32"},
      {"budget",
       ParamType::kEnum,
       "row",
       std::nullopt,
       std::nullopt,
       {"row", "global"},
       "row = k terms in every row (the paper); global = the k x rows best terms of the whole "
       "matrix by the same score, so rows with more energy get more terms (beyond the paper)"},
      {"scaling",
       ParamType::kEnum,
       "ranked",
       std::nullopt,
       std::nullopt,
       {"ranked", "always"},
       "each face's scaling coefficient (its average): ranked like the wavelets (its support is "
       "the whole face), or always kept when non-zero (counted in k)"},
      {"max_terms",
       ParamType::kInt,
       "0",
       0.0,
       1048576.0,
       {},
       "budget=global: most terms one row may get; 0: 8 k (and at most N)"},
  };
  e.device_params = {
      {"opencl_order",
       ParamType::kEnum,
       "rows",
       std::nullopt,
       std::nullopt,
       {"rows", "columns"},
       "product order on the device: rows = one work-item per row over its stored terms; "
       "columns = Ng 2003's order, one work-group per 2,048-row block reading only the columns "
       "of the light's non-zero terms (a wavelet-basis light truncated to N terms reads N "
       "columns); the column layout is derived at upload; no vertex-subset relight"},
  };
  e.light_params = {
      {"light_terms",
       ParamType::kInt,
       "0",
       0.0,
       1e9,
       {},
       "Ng 2003's light approximation at run time: keep the N Haar coefficients of the light of "
       "largest weight x |c| (the paper: 50-200); 0 = every term (the pixel light). Never "
       "recompresses"},
      {"light_weight",
       ParamType::kEnum,
       "solid_angle",
       std::nullopt,
       std::nullopt,
       {"solid_angle", "face_area", "none"},
       "the weight of the light_terms ranking: the solid angle of a coefficient's support, its "
       "area on the cube face, or none (|c| alone)"},
  };
  e.size_knob =
      SizeKnob{"k", SizeKnob::Direction::kLargerIsMoreStorage, 1.0, 512.0, SizeKnob::Scale::kLog};
  e.lossless = false;
  e.cost_hint_seconds = 1.2;  // where it was measured: docs/cli.md, "Cost hints"
  e.create = [](const ParamSet& p) -> std::unique_ptr<Compressor> {
    HaarOptions o;
    o.k = static_cast<int>(p.get_int("k"));
    o.format = p.get_enum<ValueFormat>("values", {{"float32", ValueFormat::kFloat32},
                                                  {"float16", ValueFormat::kFloat16},
                                                  {"s8", ValueFormat::kS8}});
    o.budget =
        p.get_enum<Budget>("budget", {{"row", Budget::kPerRow}, {"global", Budget::kGlobal}});
    o.scaling = p.get_enum<Scaling>("scaling",
                                    {{"ranked", Scaling::kRanked}, {"always", Scaling::kAlways}});
    o.max_terms = static_cast<int>(p.get_int("max_terms"));
    const IndexWidth index = p.get_enum<IndexWidth>(
        "index",
        {{"auto", IndexWidth::kAuto}, {"u16", IndexWidth::kU16}, {"u32", IndexWidth::kU32}});
    return std::make_unique<HaarCompressor>(o, index);
  };
  e.load = &HaarTransfer::load;
  e.version = 1;
  e.published = {
      {"chair",
       {{"k", "12"}},
       "12 wavelet terms per row: 37.1 MB (3 bytes a term), severe artifacts",
       "Sun et al. 2008, Fig. 6; their chair has 16K vertices x 64 local directions, ours the CC0 "
       "oak chair of docs/scenes.md"},
  };
  return e;
}

PRT_REGISTER_COMPRESSOR(registry_entry);

}  // namespace prt::haar
