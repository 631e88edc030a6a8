#pragma once
// Backend `uncompressed`: the exact CSR transfer T, stored as it is computed (u32 row offsets,
// u16 or u32 column ids, u8 counts times one scale 1/s^2). The reference every other backend is
// measured against, and the speed baseline for relighting (compressors/uncompressed/README.md).
//
// Parameters: only the shared "seed", which nothing here uses (the backend is deterministic).
// Device options (upload only, never saved):
//   opencl_kernel  auto | rows | lanes   which OpenCL variant upload() builds; auto picks by
//                                        device type (rows on CPUs, lanes on GPUs)
//   opencl_lanes   1..32, a power of two lanes per row of the `lanes` variant
//   opencl_skip_faces  bool              rows variant: skip dark cube faces (bit-identical)
#include <cstdint>
#include <memory>
#include <string>

#include "prtlab/compress/compressor.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/transfer/transfer_matrix.h"
#include "uncompressed/uncompressed_culled.h"

namespace prt {

struct DeviceInfo;

namespace uncompressed {

inline constexpr std::string_view kName = "uncompressed";
/// Version of this backend's archive sections and metadata (bumped when they change).
inline constexpr int kStateVersion = 2;

enum class KernelVariant { kAuto, kRows, kLanes };
std::string_view to_string(KernelVariant v);
/// The variant `kAuto` resolves to on a device (rows on CPUs, lanes otherwise).
KernelVariant resolve_variant(KernelVariant requested, const DeviceInfo& device);

struct Options {
  KernelVariant kernel = KernelVariant::kAuto;
  int lanes = 8;           ///< power of two in [1, 32]
  bool skip_faces = true;  ///< rows variant: skip the entries of cube faces the light leaves dark
};
/// The device options of upload() (ParameterError for a lane count that is no power of two).
Options options_from(const ParamSet& device_options);

class UncompressedTransfer final : public CompressedTransfer {
 public:
  explicit UncompressedTransfer(TransferMatrix transfer);
  /// The state written by save() (InputError naming the file when it is inconsistent).
  static std::unique_ptr<CompressedTransfer> load(const ArchiveReader& archive);

  const TransferMatrix& matrix() const { return t_; }

  std::string backend() const override { return std::string(kName); }
  StorageReport storage() const override;
  double flops_per_relight() const override { return 2.0 * static_cast<double>(t_.nnz()); }
  double declared_error_bound() const override { return 0.0; }
  LightCoeffs project_light(const Cubemap& radiance) const override;
  /// Skips the entries of cube faces the light leaves dark (uncompressed_culled.h): still
  /// bit-identical to relight_exact.
  void relight(const LightCoeffs& light, LocalRadiance& out) const override;
  bool supports_vertex_subset() const override { return true; }
  void relight_vertices(const LightCoeffs& light, std::span<const std::uint32_t> vertices,
                        LocalRadiance& out) const override;
  /// Where each row's faces begin (built at construction; not stored: derived from T).
  const FaceTable& faces() const { return faces_; }
  std::unique_ptr<DeviceRelighter> upload(ClContext& context,
                                          const ParamSet& device_options) const override;
  void save(ArchiveWriter& archive) const override;

 private:
  TransferMatrix t_;
  FaceTable faces_;
};

/// T resident on `context`'s device, relit by the variant `options` asks for (resolved with
/// resolve_variant). The context must outlive the returned relighter.
/// `faces` (may be empty: no face skipping) is uploaded for the rows variant, which skips dark
/// faces and relights vertex subsets; the lanes variant does neither (its reduction order has no
/// subset kernel yet), and says so in supports_vertex_subset().
std::unique_ptr<DeviceRelighter> upload_transfer(ClContext& context, const TransferMatrix& transfer,
                                                 const Options& options,
                                                 const FaceTable* faces = nullptr);

/// The registry entry (registered by uncompressed.cpp).
CompressorEntry registry_entry();

}  // namespace uncompressed
}  // namespace prt
