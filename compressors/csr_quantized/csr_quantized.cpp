#include "csr_quantized/csr_quantized.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "csr_quantized/half_decode.h"
#include "prtlab/base/error.h"
#include "prtlab/storage/archive.h"

namespace prt::csr_quantized {
namespace {

class CsrQuantizedCompressor final : public Compressor {
 public:
  explicit CsrQuantizedCompressor(ValueFormat format) : format_(format) {}

  std::unique_ptr<CompressedTransfer> compress(const TransferInput& input,
                                               Progress& progress) const override {
    check_transfer_shape(input, kName);
    auto out = std::make_unique<CsrQuantizedTransfer>(quantize(input.transfer, format_));
    progress.finish();
    return out;
  }

 private:
  ValueFormat format_;
};

}  // namespace

std::string_view to_string(ValueFormat f) {
  switch (f) {
    case ValueFormat::kFloat32:
      return "float32";
    case ValueFormat::kFloat16:
      return "float16";
    case ValueFormat::kU8:
      return "u8";
  }
  return "?";
}

ValueFormat value_format_from(std::string_view name) {
  for (ValueFormat f : {ValueFormat::kFloat32, ValueFormat::kFloat16, ValueFormat::kU8})
    if (to_string(f) == name) return f;
  throw ParameterError(
      fmt::format("{}: value format '{}' is none of float32, float16, u8", kName, name));
}

StorageReport CsrQuantizedTransfer::storage() const {
  const std::uint64_t nnz = q_.nnz();
  StorageReport r;
  r.components.push_back(
      {"row_offsets", (q_.rows() + 1) * std::uint64_t{4},
       "u32 per row + 1: index of the row's first entry in columns/values (CSR), last = nnz"});
  r.components.push_back(
      {"columns", nnz * q_.column_bytes(),
       fmt::format("{} per non-zero: global pixel k (cubemap order), strictly increasing in a row",
                   q_.narrow_columns() ? "u16" : "u32")});
  switch (q_.format) {
    case ValueFormat::kFloat32:
      r.components.push_back({"values", nnz * 4, "f32 per non-zero: the value c / s^2"});
      break;
    case ValueFormat::kFloat16:
      r.components.push_back(
          {"values", nnz * 2, "IEEE half per non-zero: c / s^2 rounded to nearest even"});
      break;
    case ValueFormat::kU8:
      r.components.push_back(
          {"values", nnz, "u8 code q per non-zero: value = q * the row's scale, q in 0..255"});
      r.components.push_back({"row_scales", q_.rows() * std::uint64_t{4},
                              "f32 per row: the row's largest value / 255 (the value of q = 1)"});
      break;
  }
  return r;
}

double CsrQuantizedTransfer::flops_per_relight() const {
  // The exact product's 1/s^2 is not counted (compressor.h): one common factor, it could be
  // folded into the light. The u8 row scales differ per row, so each costs a multiply.
  const double scales = q_.format == ValueFormat::kU8 ? static_cast<double>(q_.rows()) : 0.0;
  return 2.0 * static_cast<double>(q_.nnz()) + scales;
}

double CsrQuantizedTransfer::declared_error_bound() const {
  return q_.format == ValueFormat::kFloat32 ? 0.0 : q_.max_entry_error;
}

LightCoeffs CsrQuantizedTransfer::project_light(const Cubemap& radiance) const {
  return pixel_light(radiance, static_cast<std::size_t>(q_.pixel_count), kName);
}

void CsrQuantizedTransfer::relight(const LightCoeffs& light, LocalRadiance& out) const {
  check_pixel_light(light, static_cast<std::size_t>(q_.pixel_count), kName);
  out.ensure_shape(RadianceBasis::kPixel, q_.local_count, q_.vertices);
  relight_quantized(q_, light.values, out.values);
}

void CsrQuantizedTransfer::relight_vertices(const LightCoeffs& light,
                                            std::span<const std::uint32_t> vertices,
                                            LocalRadiance& out) const {
  check_pixel_light(light, static_cast<std::size_t>(q_.pixel_count), kName);
  check_vertex_subset(vertices, q_.vertices, kName);
  out.ensure_shape(RadianceBasis::kPixel, q_.local_count, q_.vertices);
  relight_quantized_vertices(q_, light.values, vertices, out.values);
}

std::unique_ptr<DeviceRelighter> CsrQuantizedTransfer::upload(ClContext& context,
                                                              const ParamSet&) const {
  return upload_quantized(context, q_);
}

void CsrQuantizedTransfer::save(ArchiveWriter& archive) const {
  archive.add_meta("csr_quantized_version", kStateVersion);
  archive.add_meta("vertices", q_.vertices);
  archive.add_meta("local_count", q_.local_count);
  archive.add_meta("pixel_count", q_.pixel_count);
  archive.add_meta("values", std::string(to_string(q_.format)));
  archive.add_meta("max_entry_error", q_.max_entry_error);
  archive.add_meta("frobenius_error", q_.frobenius_error);
  archive.add_section("row_offsets", q_.offsets);
  if (q_.narrow_columns()) {
    archive.add_section("columns", q_.columns16);
  } else {
    archive.add_section("columns", q_.columns32);
  }
  switch (q_.format) {
    case ValueFormat::kFloat32:
      archive.add_section("values", q_.values32);
      break;
    case ValueFormat::kFloat16:
      archive.add_section("values", q_.values16);
      break;
    case ValueFormat::kU8:
      archive.add_section("values", q_.codes);
      archive.add_section("row_scales", q_.row_scales);
      break;
  }
}

std::unique_ptr<CompressedTransfer> CsrQuantizedTransfer::load(const ArchiveReader& r) {
  const auto fail = [&](const std::string& problem) {
    return InputError(r.path(), fmt::format("{}: {}", kName, problem));
  };
  const int version = r.meta_value<int>("csr_quantized_version");
  if (version != kStateVersion)
    throw fail(fmt::format("state version {} is not the version {} this build reads", version,
                           kStateVersion));
  QuantizedCsr q;
  q.vertices = r.meta_value<std::size_t>("vertices");
  q.local_count = r.meta_value<int>("local_count");
  q.pixel_count = r.meta_value<int>("pixel_count");
  q.max_entry_error = r.meta_value<double>("max_entry_error");
  q.frobenius_error = r.meta_value<double>("frobenius_error");
  try {
    q.format = value_format_from(r.meta_value<std::string>("values"));
  } catch (const ParameterError& e) {
    throw fail(e.what());
  }
  if (q.local_count <= 0 || q.pixel_count <= 0)
    throw fail(fmt::format("bad shape: M = {}, N = {}", q.local_count, q.pixel_count));
  if (!(std::isfinite(q.max_entry_error) && q.max_entry_error >= 0 &&
        std::isfinite(q.frobenius_error) && q.frobenius_error >= 0))
    throw fail("the error statistics are not finite non-negative numbers");
  if (q.vertices >
      std::numeric_limits<std::uint32_t>::max() / static_cast<std::uint64_t>(q.local_count))
    throw fail(fmt::format("{} vertices x M = {} rows do not fit the relight's u32 row index",
                           q.vertices, q.local_count));
  const std::uint64_t rows = q.vertices * static_cast<std::uint64_t>(q.local_count);
  q.offsets = r.section<std::uint32_t>("row_offsets", rows + 1);
  // The kernel trusts these arrays: a file that passed the checksum but was written wrong must
  // still not make it read out of bounds.
  if (q.offsets.front() != 0 || !std::is_sorted(q.offsets.begin(), q.offsets.end()))
    throw fail("row offsets do not rise from 0");
  const std::uint64_t nnz = q.offsets.back();
  const auto out_of_range = [&](std::uint32_t c) {
    return c >= static_cast<std::uint32_t>(q.pixel_count);
  };
  if (q.narrow_columns()) {
    q.columns16 = r.section<std::uint16_t>("columns", nnz);
    if (std::any_of(q.columns16.begin(), q.columns16.end(), out_of_range))
      throw fail(fmt::format("a column index is out of range (N = {})", q.pixel_count));
  } else {
    q.columns32 = r.section<std::uint32_t>("columns", nnz);
    if (std::any_of(q.columns32.begin(), q.columns32.end(), out_of_range))
      throw fail(fmt::format("a column index is out of range (N = {})", q.pixel_count));
  }
  const auto finite = [](float v) { return std::isfinite(v); };
  switch (q.format) {
    case ValueFormat::kFloat32:
      q.values32 = r.section<float>("values", nnz);
      if (!std::all_of(q.values32.begin(), q.values32.end(), finite))
        throw fail("a value is not finite");
      break;
    case ValueFormat::kFloat16:
      q.values16 = r.section<std::uint16_t>("values", nnz);
      if (!std::all_of(q.values16.begin(), q.values16.end(), is_finite_half))
        throw fail("a half value is infinite or NaN");
      break;
    case ValueFormat::kU8:
      q.codes = r.section<std::uint8_t>("values", nnz);
      q.row_scales = r.section<float>("row_scales", rows);
      if (!std::all_of(q.row_scales.begin(), q.row_scales.end(), finite))
        throw fail("a row scale is not finite");
      break;
  }
  return std::make_unique<CsrQuantizedTransfer>(std::move(q));
}

CompressorEntry registry_entry() {
  CompressorEntry e;
  e.name = std::string(kName);
  e.description =
      "baseline: T's CSR as a generic float sparse matrix, values as float32, float16 or u8 "
      "codes x a per-row f32 scale (lossless at the default float32)";
  e.params = {
      {"values",
       ParamType::kEnum,
       "float32",
       std::nullopt,
       std::nullopt,
       {"float32", "float16", "u8"},
       "value format: float32 = c/s^2 as f32 (lossless), float16 = IEEE half (round to nearest "
       "even), u8 = code q in 0..255 times a per-row f32 scale max_row/255 (round to nearest)"},
  };
  // No size knob: `values` is an enum, and a knob must be an int or real parameter.
  e.lossless = true;          // at the default values=float32
  e.cost_hint_seconds = 0.2;  // where it was measured: docs/cli.md, "Cost hints"
  e.create = [](const ParamSet& p) -> std::unique_ptr<Compressor> {
    return std::make_unique<CsrQuantizedCompressor>(
        p.get_enum<ValueFormat>("values", {{"float32", ValueFormat::kFloat32},
                                           {"float16", ValueFormat::kFloat16},
                                           {"u8", ValueFormat::kU8}}));
  };
  e.load = &CsrQuantizedTransfer::load;
  return e;
}

PRT_REGISTER_COMPRESSOR(registry_entry);

}  // namespace prt::csr_quantized
