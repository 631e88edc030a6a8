#pragma once
// Backend `bicluster`: the biclustering of T of Sun et al. (bicluster_search.h), relit in two
// phases per Algorithm 2: phase 1 one RGB scalar P_i = sum_m t_m L[k_m] per bicluster, phase 2
// per row the sum of P_i over the biclusters touching it, times 1/s^2. Residual 1x1 terms are
// stored as 1x1 biclusters (W = 1 + 2 - 1 = 2 FLOPs, as the paper counts a residual term), so
// phase 2 has one loop.
//
// Phase 2's layout is sliced ELLPACK (SELL-4, the GPU sparse format): T's rows, in an order
// that puts rows sharing biclusters next to each other, form slices of 4 rows, each slice
// padded to its longest row with steps onto a zero product, its entries interleaved step by
// step and stored as u16 id deltas. A slice is one loop of fixed length with 4 independent
// gathers per step: rows of varying length (0 to ~50 biclusters, ~17 on average) would
// otherwise cost a mispredicted loop exit per row, which measured as much as the gathers
// themselves. compressors/bicluster/README.md gives the byte layout and the measurements.
//
// Parameters: "groups" (row groups searched in parallel, bicluster_search.h), "error" (the lossy
// mode's relative L1 budget, bicluster_budget.h; 0 = lossless), "opencl_ids" (the device's id
// stream) and the shared "seed".
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "bicluster/bicluster_search.h"
#include "prtlab/compress/compressor.h"
#include "prtlab/compress/compressor_registry.h"

namespace prt {

class TransferMatrix;

namespace bicluster {

inline constexpr std::string_view kName = "bicluster";
/// Version of this backend's archive sections and metadata (bumped when they change).
inline constexpr int kStateVersion = 4;
/// Default of the "groups" parameter (compressors/bicluster/README.md has the measurements).
inline constexpr int kDefaultGroups = 2;
/// Rows per slice of phase 2.
inline constexpr int kSliceRows = 4;
/// Phase 2's row order sorts rows by length within windows of this many rows (a multiple of
/// kSliceRows): less padding than windows of 16 or 64 (9.47 MB stored on the bunny, against
/// 10.06 and 9.61 MB), no difference in relight time we could separate from noise.
inline constexpr std::size_t kRowWindow = 256;
/// Bicluster ids that are multiples of this are zero slots: empty biclusters (no columns, so
/// P = 0) that a lane steps on to pad or to cross a gap of 2^16 ids or more.
inline constexpr std::uint32_t kZeroStride = 0x8000;

/// Phase 2's id stream on the device (device option "opencl_ids"): the stored u16 deltas decoded
/// in the kernel, or expanded at upload to u32 ids (twice the bytes, no decoding); auto picks
/// by device type (compressors/bicluster/README.md has the measurements).
enum class DeviceIds { kAuto, kU16, kU32 };
std::string_view to_string(DeviceIds ids);

/// The stored form (the arrays of compressors/bicluster/README.md).
struct BiclusterArrays {
  std::size_t vertices = 0;
  int local_count = 0;  ///< M
  int pixel_count = 0;  ///< N
  int supersampling = 1;
  double error = 0.0;  ///< the lossy mode's budget E (parameter "error"; 0 = lossless)
  double bound = 0.0;  ///< relative L1 bound actually used (<= error; 0 when lossless)
  // Phase 1: bicluster i has columns [bic_col_offsets[i], bic_col_offsets[i + 1]).
  std::vector<std::uint32_t> bic_col_offsets{0};  ///< per bicluster + 1
  std::vector<std::uint32_t> bic_columns;         ///< global pixel k, increasing per bicluster
  std::vector<std::int16_t> bic_constants;        ///< t_m as signed counts
  // Phase 2: slice s holds codes [slice_offsets[s], slice_offsets[s + 1]), a multiple of 4:
  // step q, lane c at offset + 4 q + c. Lane c is row slice_rows[4 s + c] of T (rows(): no
  // row); the slices list every row once, in phase 2's row order (bicluster.cpp). A lane
  // starts at id slice_base[s]; each step adds its code to the lane's id and then P_id. Steps
  // onto a zero slot add nothing: they pad a lane shorter than the slice and cross gaps the u16
  // codes cannot (each slot is within 2^15 of the next).
  std::vector<std::uint32_t> slice_offsets{0};  ///< per slice + 1
  std::vector<std::uint32_t> slice_rows;        ///< per slice x 4 lanes: row, or rows()
  std::vector<std::uint32_t> slice_base;        ///< per slice: the smallest first id of a lane
  std::vector<std::uint16_t> slice_codes;       ///< per slice step x 4 lanes: id delta

  std::size_t rows() const { return vertices * static_cast<std::size_t>(local_count); }
  std::size_t bicluster_count() const { return bic_col_offsets.size() - 1; }
  /// Slices that hold rows() rows, 4 per slice.
  std::size_t slice_count_for_rows() const { return (rows() + kSliceRows - 1) / kSliceRows; }
  std::size_t slice_count() const { return slice_offsets.size() - 1; }
  /// Biclusters without the zero slots (ids 0, kZeroStride, 2 kZeroStride, ... < count).
  std::size_t real_bicluster_count() const {
    return bicluster_count() - (bicluster_count() + kZeroStride - 1) / kZeroStride;
  }
  /// Products phase 1 provides: the biclusters, then up to the zero slot at or above the
  /// count (a lane pads on the next slot above its last id). Only that last slot is read.
  std::size_t product_count() const {
    return (bicluster_count() + kZeroStride - 1) / kZeroStride * kZeroStride + 1;
  }
  /// (row, bicluster) incidences: the steps onto real biclusters.
  std::size_t incidences() const;
  /// Calls f(id) for each bicluster id (zero slots skipped) of lane `lane` of slice s, in
  /// increasing order.
  template <typename F>
  void for_each_id(std::size_t s, int lane, F&& f) const {
    std::uint32_t id = slice_base[s];
    for (std::uint32_t q = slice_offsets[s] + static_cast<std::uint32_t>(lane);
         q < slice_offsets[s + 1]; q += kSliceRows) {
      id += slice_codes[q];
      if (id % kZeroStride != 0) f(id);
    }
  }
  double scale() const { return 1.0 / (static_cast<double>(supersampling) * supersampling); }
};

/// T's counts as the search's signed CSR.
SparseCounts counts_of(const TransferMatrix& t);
/// Pack a search result: residual terms consolidated and stored as 1x1 biclusters; rows in
/// phase 2's row order (rows sharing their largest bicluster adjacent, so that consecutive
/// slices gather the same products), sliced as above; biclusters numbered by first use in that
/// order (a slice's gathers near each other, its u16 deltas small), skipping the zero slots.
BiclusterArrays pack(const Biclustering& b, const TransferMatrix& t);
/// The counts the arrays stand for (the sum of their biclusters).
SparseCounts reconstruct(const BiclusterArrays& a);

class BiclusterTransfer final : public CompressedTransfer {
 public:
  explicit BiclusterTransfer(BiclusterArrays arrays);
  static std::unique_ptr<CompressedTransfer> load(const ArchiveReader& archive);

  const BiclusterArrays& arrays() const { return a_; }
  std::string backend() const override { return std::string(kName); }
  StorageReport storage() const override;
  /// sum W(B_i) = sum (r_i + 2 l_i - 1), residual terms included as 1x1 biclusters (2 each);
  /// the zero slots and the steps onto them are not counted (they add zeros).
  double flops_per_relight() const override;
  /// Relative L1 (bicluster_budget.h): max over columns of the dropped mass over T's column mass.
  double declared_error_bound() const override { return a_.bound; }
  ErrorNorm declared_error_norm() const override { return ErrorNorm::kRelativeL1; }
  LightCoeffs project_light(const Cubemap& radiance) const override;
  /// Phase 1 skips biclusters whose columns all lie on faces the light leaves dark
  /// (bicluster_culling.h): bit-identical.
  void relight(const LightCoeffs& light, LocalRadiance& out) const override;
  /// relight() with phase 1 reading the biclusters that touch the faces in `lit` only
  /// (relight() passes lit_faces(light); kAllFaces skips nothing, for comparisons).
  void relight_faces(const LightCoeffs& light, std::uint32_t lit, LocalRadiance& out) const;
  /// Phase 2 over the slices holding the vertices' rows, storing only those rows; phase 1 whole
  /// (bicluster_culling.h says why).
  bool supports_vertex_subset() const override { return true; }
  void relight_vertices(const LightCoeffs& light, std::span<const std::uint32_t> vertices,
                        LocalRadiance& out) const override;
  std::unique_ptr<DeviceRelighter> upload(ClContext& context,
                                          const ParamSet& device_options) const override;
  void save(ArchiveWriter& archive) const override;

 private:
  bool narrow() const { return a_.pixel_count <= 65536; }
  bool narrow_rows() const { return a_.rows() < 65535; }  // rows and the sentinel fit a u16
  // out = the shape relight() writes; the products P of phase 1 (float4 RGB + pad each).
  void prepare_output(LocalRadiance& out) const;
  void phase1(const LightCoeffs& light, std::uint32_t lit, float* products) const;
  // Phase 2 of slices[0..count) (all slices when `slices` is null), storing the lanes whose bit
  // is set in lanes[i] (all lanes when `lanes` is null).
  void phase2(const float* products, const std::uint32_t* slices, const std::uint8_t* lanes,
              std::size_t count, LocalRadiance& out) const;

  BiclusterArrays a_;
  std::size_t incidences_ = 0;
  // Derived at construction, not stored (bicluster_culling.h): the cube faces of each
  // bicluster's columns (1 byte per bicluster) and each row's lane in phase 2 (4 bytes per row).
  std::vector<std::uint8_t> faces_;
  std::vector<std::uint32_t> row_lanes_;
};

/// `skip_faces`: phase 1 skips the biclusters on cube faces the light leaves dark (device option
/// opencl_skip_faces; bit-identical either way).
std::unique_ptr<DeviceRelighter> upload_arrays(ClContext& context, const BiclusterArrays& a,
                                               DeviceIds device_ids = DeviceIds::kAuto,
                                               bool skip_faces = true);

CompressorEntry registry_entry();

}  // namespace bicluster
}  // namespace prt
