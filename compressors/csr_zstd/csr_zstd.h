#pragma once
// Backend `csr_zstd`: the exact CSR of `uncompressed` (u32 row offsets, u16 or u32 columns, u8
// counts times 1/s^2) compressed with zstd, in frames of `block_rows` rows that are compressed
// and decompressed independently (compressors/csr_zstd/README.md). Every relight decompresses
// every frame it needs (all of them, or those holding a row of a vertex subset): the relight
// time is what general-purpose compression costs.
//
// Parameters: `level` (zstd level 1..19, the size knob) and `block_rows` (rows per frame).
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "prtlab/compress/compressor.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt::csr_zstd {

inline constexpr std::string_view kName = "csr_zstd";
/// Version of this backend's archive sections and metadata (bumped when they change).
inline constexpr int kStateVersion = 1;

/// T in zstd frames. Frame f covers rows [f * block_rows, min(rows, (f + 1) * block_rows)) and
/// entries [frame_entries[f], frame_entries[f + 1]); decompressed it holds, back to back, the
/// rows' u32 row offsets including the frame's end (rows + 1 values, absolute in T), their
/// columns (u16 when N <= 65536, else u32) and their u8 counts.
struct FramedCsr {
  std::size_t vertices = 0;
  int local_count = 0;    ///< M
  int pixel_count = 0;    ///< N
  int supersampling = 1;  ///< s: a count c is worth c / s^2
  int block_rows = 1024;
  int level = 3;
  std::vector<std::uint8_t> frames;             ///< the zstd frames, concatenated
  std::vector<std::uint64_t> frame_offsets{0};  ///< frames + 1: byte offset of each frame
  std::vector<std::uint32_t> frame_entries{0};  ///< frames + 1: first entry of each frame

  std::size_t rows() const { return vertices * static_cast<std::size_t>(local_count); }
  std::size_t nnz() const { return frame_entries.back(); }
  std::size_t frame_count() const { return frame_offsets.size() - 1; }
  std::size_t frame_row_begin(std::size_t f) const { return f * block_rows; }
  std::size_t frame_row_end(std::size_t f) const;
  bool narrow_columns() const { return pixel_count <= 65536; }
  std::size_t column_bytes() const { return narrow_columns() ? 2 : 4; }
  double scale() const { return 1.0 / (static_cast<double>(supersampling) * supersampling); }
  /// Bytes of frame f decompressed.
  std::size_t frame_raw_bytes(std::size_t f) const;
};

/// T compressed at zstd `level` in frames of `block_rows` rows (deterministic; frames are
/// compressed in parallel). `progress` advances by each frame's rows.
FramedCsr compress_frames(const TransferMatrix& t, int level, int block_rows, Progress& progress);

/// One decompressed frame, valid until the same thread decodes again with the same decoder.
struct FrameView {
  std::size_t row_begin = 0, row_end = 0;        ///< rows of T
  std::uint32_t entry_begin = 0, entry_end = 0;  ///< entries of T
  const std::uint32_t* offsets = nullptr;        ///< row_end - row_begin + 1, absolute
  const std::uint16_t* columns16 = nullptr;      ///< entry_end - entry_begin, narrow
  const std::uint32_t* columns32 = nullptr;      ///< entry_end - entry_begin, wide
  const std::uint8_t* counts = nullptr;          ///< entry_end - entry_begin
};

/// Decompresses frames into a per-thread scratch buffer with a per-thread zstd context, so that
/// one decoder serves a parallel loop over frames. Thread-safe.
class FrameDecoder {
 public:
  FrameDecoder();
  ~FrameDecoder();
  FrameDecoder(const FrameDecoder&) = delete;
  FrameDecoder& operator=(const FrameDecoder&) = delete;

  /// Frame f of `csr`. A frame that does not decompress to its declared size, or whose first
  /// and last row offsets are not its entry range, is a ParameterError naming the frame.
  FrameView decode(const FramedCsr& csr, std::size_t f) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A frame a vertex subset needs, and the subset's vertices [vertex_begin, vertex_end) that have
/// a row in it.
struct FrameTask {
  std::size_t frame = 0;
  std::size_t vertex_begin = 0, vertex_end = 0;
};
/// The frames holding a row of `vertices` (sorted, unique, checked by the caller), increasing.
/// A vertex whose rows straddle a frame boundary is listed in both frames.
std::vector<FrameTask> frame_tasks(const FramedCsr& csr, std::span<const std::uint32_t> vertices);

/// The exact T back from every frame (validated by TransferMatrix::from_csr: ParameterError).
TransferMatrix decompress_all(const FramedCsr& csr);

class CsrZstdTransfer final : public CompressedTransfer {
 public:
  explicit CsrZstdTransfer(FramedCsr csr);
  /// The state written by save() (InputError naming the file when it is inconsistent).
  static std::unique_ptr<CompressedTransfer> load(const ArchiveReader& archive);

  const FramedCsr& frames() const { return *csr_; }

  std::string backend() const override { return std::string(kName); }
  StorageReport storage() const override;
  double flops_per_relight() const override { return 2.0 * static_cast<double>(csr_->nnz()); }
  double declared_error_bound() const override { return 0.0; }
  LightCoeffs project_light(const Cubemap& radiance) const override;
  /// Decompresses every frame (TBB over frames, one scratch buffer per thread) and multiplies.
  void relight(const LightCoeffs& light, LocalRadiance& out) const override;
  /// Decompresses only the frames holding a row of `vertices` and relights those rows.
  bool supports_vertex_subset() const override { return true; }
  void relight_vertices(const LightCoeffs& light, std::span<const std::uint32_t> vertices,
                        LocalRadiance& out) const override;
  std::unique_ptr<DeviceRelighter> upload(ClContext& context,
                                          const ParamSet& device_options) const override;
  void save(ArchiveWriter& archive) const override;

 private:
  // Shared with the device relighters, which decompress on the host at every relight.
  std::shared_ptr<const FramedCsr> csr_;
  std::shared_ptr<const FrameDecoder> decoder_;
};

/// The host-decompressing relighter on `context`'s device (csr_zstd_opencl.cpp). The context
/// must outlive it.
std::unique_ptr<DeviceRelighter> upload_frames(ClContext& context,
                                               std::shared_ptr<const FramedCsr> csr);

/// The registry entry (registered by csr_zstd.cpp).
CompressorEntry registry_entry();

}  // namespace prt::csr_zstd
