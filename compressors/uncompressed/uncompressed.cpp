#include "uncompressed/uncompressed.h"

#include <bit>

#include "prtlab/base/error.h"
#include "prtlab/opencl/cl_device.h"
#include "prtlab/sphere/lit_faces.h"
#include "prtlab/storage/archive.h"
#include "prtlab/transfer/exact_relight.h"

namespace prt::uncompressed {
namespace {

class UncompressedCompressor final : public Compressor {
 public:
  std::unique_ptr<CompressedTransfer> compress(const TransferInput& input,
                                               Progress& progress) const override {
    check_transfer_shape(input, kName);
    auto out = std::make_unique<UncompressedTransfer>(input.transfer);
    progress.finish();
    return out;
  }
};

std::string column_type(const TransferMatrix& t) {
  return t.narrow_columns() ? "u16" : "u32";
}

}  // namespace

Options options_from(const ParamSet& params) {
  Options o;
  o.kernel = params.get_enum<KernelVariant>("opencl_kernel", {{"auto", KernelVariant::kAuto},
                                                              {"rows", KernelVariant::kRows},
                                                              {"lanes", KernelVariant::kLanes}});
  o.lanes = static_cast<int>(params.get_int("opencl_lanes"));
  o.skip_faces = params.get_bool("opencl_skip_faces");
  // The range is checked by ParamSet; the power of two is the reduction's requirement.
  if (!std::has_single_bit(static_cast<unsigned>(o.lanes)))
    throw ParameterError(
        fmt::format("{}: parameter opencl_lanes={}: must be a power of two (1, 2, 4, ..., 32)",
                    kName, o.lanes));
  return o;
}

std::string_view to_string(KernelVariant v) {
  switch (v) {
    case KernelVariant::kAuto:
      return "auto";
    case KernelVariant::kRows:
      return "rows";
    case KernelVariant::kLanes:
      return "lanes";
  }
  return "?";
}

KernelVariant resolve_variant(KernelVariant requested, const DeviceInfo& device) {
  if (requested != KernelVariant::kAuto) return requested;
  // Measured on PoCL (compressors/uncompressed/README.md): a work-item per row matches the C++
  // loop, lanes cost barriers that PoCL turns into work-item loops. On GPUs, lanes give coalesced
  // reads.
  return device.is_cpu ? KernelVariant::kRows : KernelVariant::kLanes;
}

UncompressedTransfer::UncompressedTransfer(TransferMatrix transfer)
    : t_(std::move(transfer)), faces_(t_) {}

StorageReport UncompressedTransfer::storage() const {
  const std::uint64_t nnz = t_.nnz();
  const std::uint64_t col_bytes = t_.narrow_columns() ? 2 : 4;
  StorageReport r;
  r.components.push_back(
      {"row_offsets", (t_.rows() + 1) * std::uint64_t{4},
       "u32 per row + 1: index of the row's first entry in columns/counts (CSR), last = nnz"});
  r.components.push_back(
      {"columns", nnz * col_bytes,
       fmt::format("{} per non-zero: global pixel k (cubemap order), strictly increasing in a row",
                   column_type(t_))});
  r.components.push_back(
      {"counts", nnz, "u8 per non-zero: unblocked sub-rays c in 1..s^2; value = c * scale"});
  r.components.push_back(
      {"scale", 4, "f32 once: the value of a count of 1, 1/s^2 (stored as s in the metadata)"});
  return r;
}

LightCoeffs UncompressedTransfer::project_light(const Cubemap& radiance) const {
  return pixel_light(radiance, t_.cols(), kName);
}

void UncompressedTransfer::relight(const LightCoeffs& light, LocalRadiance& out) const {
  check_pixel_light(light, t_.cols(), kName);
  out.ensure_shape(RadianceBasis::kPixel, t_.local_count(), t_.vertex_count());
  const std::uint32_t lit = lit_faces(light.values);
  if (lit == kAllFaces || faces_.empty()) {
    relight_exact(t_, light.values, out.values);
  } else {
    relight_culled(t_, faces_, light.values, lit, true, {}, out.values);
  }
}

void UncompressedTransfer::relight_vertices(const LightCoeffs& light,
                                            std::span<const std::uint32_t> vertices,
                                            LocalRadiance& out) const {
  check_pixel_light(light, t_.cols(), kName);
  check_vertex_subset(vertices, t_.vertex_count(), kName);
  out.ensure_shape(RadianceBasis::kPixel, t_.local_count(), t_.vertex_count());
  relight_culled(t_, faces_, light.values, lit_faces(light.values), false, vertices, out.values);
}

std::unique_ptr<DeviceRelighter> UncompressedTransfer::upload(
    ClContext& context, const ParamSet& device_options) const {
  return upload_transfer(context, t_, options_from(device_options), &faces_);
}

void UncompressedTransfer::save(ArchiveWriter& archive) const {
  archive.add_meta("uncompressed_version", kStateVersion);
  archive.add_meta("vertices", t_.vertex_count());
  archive.add_meta("local_count", t_.local_count());
  archive.add_meta("pixel_count", t_.cols());
  archive.add_meta("supersampling", t_.supersampling());
  archive.add_section("row_offsets", t_.row_offsets());
  if (t_.narrow_columns()) {
    archive.add_section("columns", t_.columns16());
  } else {
    archive.add_section("columns", t_.columns32());
  }
  archive.add_section("counts", t_.counts());
}

std::unique_ptr<CompressedTransfer> UncompressedTransfer::load(const ArchiveReader& r) {
  const int version = r.meta_value<int>("uncompressed_version");
  if (version != kStateVersion)
    throw InputError(
        r.path(), fmt::format("{} state version {} is not the version {} this build reads", kName,
                              version, kStateVersion));
  const auto vertices = r.meta_value<std::size_t>("vertices");
  const int m = r.meta_value<int>("local_count");
  const int n = r.meta_value<int>("pixel_count");
  const int s = r.meta_value<int>("supersampling");
  const std::vector<std::uint32_t> columns = r.indices("columns");
  try {
    TransferMatrix t =
        TransferMatrix::from_csr(vertices, m, n, s, r.section<std::uint32_t>("row_offsets"),
                                 columns, r.section<std::uint8_t>("counts", columns.size()));
    return std::make_unique<UncompressedTransfer>(std::move(t));
  } catch (const ParameterError& e) {
    throw InputError(r.path(), e.what());
  }
}

CompressorEntry registry_entry() {
  CompressorEntry e;
  e.name = std::string(kName);
  e.description =
      "exact CSR transfer (u32 row offsets, u16 columns, u8 counts x 1/s^2): the lossless "
      "reference";
  e.device_params = {
      {"opencl_kernel",
       ParamType::kEnum,
       "auto",
       std::nullopt,
       std::nullopt,
       {"auto", "rows", "lanes"},
       "OpenCL variant: rows = one work-item per row (CPUs), lanes = opencl_lanes work-items per "
       "row with a "
       "local-memory reduction (GPUs), auto = by device type"},
      {"opencl_lanes",
       ParamType::kInt,
       "8",
       1.0,
       32.0,
       {},
       "work-items per row of the lanes variant (a power of two)"},
      {"opencl_skip_faces",
       ParamType::kBool,
       "true",
       std::nullopt,
       std::nullopt,
       {},
       "rows variant: skip the entries on cube faces the light leaves black (bit-identical; "
       "false sums them, for comparisons)"},
  };
  e.lossless = true;
  e.cost_hint_seconds = 0.04;  // where it was measured: docs/cli.md, "Cost hints"
  // 2: the device options left the saved state.
  e.version = 2;
  e.create = [](const ParamSet&) -> std::unique_ptr<Compressor> {
    return std::make_unique<UncompressedCompressor>();
  };
  e.load = &UncompressedTransfer::load;
  return e;
}

PRT_REGISTER_COMPRESSOR(registry_entry);

}  // namespace prt::uncompressed
