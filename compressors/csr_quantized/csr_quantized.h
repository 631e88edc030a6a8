#pragma once
// Backend `csr_quantized`: T's sparsity (u32 row offsets, T's u16 or u32 columns) with the values
// stored the way a generic sparse-matrix library would hold them, then quantised
// (compressors/csr_quantized/README.md):
//
//   float32  v as an IEEE float (what Eigen or cuSPARSE keep): lossless w.r.t. T's values
//   float16  v as an IEEE half, round to nearest even
//   u8       v ~ q * scale_row, q = round(v / scale_row) in 0..255, scale_row = max_row / 255
//
// Error bound. With rho = max over stored entries of |v~ - v| / v, every row and channel of a
// non-negative light obeys |(T~ L - T L)_i| <= sum_k |v~_ik - v_ik| L_k <= rho (T L)_i, hence
// ||T~ L - T L||_2 <= rho ||T L||_2. rho is computed in double from the stored values.
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "prtlab/compress/compressor.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt::csr_quantized {

inline constexpr std::string_view kName = "csr_quantized";
/// Version of this backend's archive sections and metadata (bumped when they change).
inline constexpr int kStateVersion = 1;

enum class ValueFormat { kFloat32, kFloat16, kU8 };
std::string_view to_string(ValueFormat f);
/// The format named `name` ("float32", "float16", "u8"); ParameterError otherwise.
ValueFormat value_format_from(std::string_view name);

/// T's sparsity with quantised values: the arrays both relight paths read.
struct QuantizedCsr {
  std::size_t vertices = 0;
  int local_count = 0;  ///< M
  int pixel_count = 0;  ///< N
  ValueFormat format = ValueFormat::kFloat32;
  std::vector<std::uint32_t> offsets{0};  ///< rows + 1
  std::vector<std::uint16_t> columns16;   ///< nnz, when N <= 65536
  std::vector<std::uint32_t> columns32;   ///< nnz, when N > 65536
  std::vector<float> values32;            ///< nnz, format float32
  std::vector<std::uint16_t> values16;    ///< nnz, format float16: IEEE half bits
  std::vector<std::uint8_t> codes;        ///< nnz, format u8
  std::vector<float> row_scales;          ///< rows, format u8: the value of code 1
  /// max |v~ - v| / v over the stored entries (the rho of the header), in double.
  double max_entry_error = 0;
  /// ||T~ - T||_F / ||T||_F, in double (0 for an all-zero T).
  double frobenius_error = 0;

  std::size_t rows() const { return offsets.size() - 1; }
  std::size_t nnz() const { return offsets.back(); }
  bool narrow_columns() const { return pixel_count <= 65536; }
  std::size_t column_bytes() const { return narrow_columns() ? 2 : 4; }
  std::size_t value_bytes() const;
};

/// T's values in `format`, with the error statistics of the result.
QuantizedCsr quantize(const TransferMatrix& t, ValueFormat format);

/// out = T~ light (TBB over rows; four accumulators per row, summed as the kernel sums).
void relight_quantized(const QuantizedCsr& q, std::span<const Rgb> light, std::span<Rgb> out);
/// The rows vertex * M .. vertex * M + M - 1 of out = T~ light for the given vertices (sorted,
/// unique, checked by the caller), with relight_quantized's bits; other rows are not written.
void relight_quantized_vertices(const QuantizedCsr& q, std::span<const Rgb> light,
                                std::span<const std::uint32_t> vertices, std::span<Rgb> out);

class CsrQuantizedTransfer final : public CompressedTransfer {
 public:
  explicit CsrQuantizedTransfer(QuantizedCsr arrays) : q_(std::move(arrays)) {}
  /// The state written by save() (InputError naming the file when it is inconsistent).
  static std::unique_ptr<CompressedTransfer> load(const ArchiveReader& archive);

  const QuantizedCsr& arrays() const { return q_; }

  std::string backend() const override { return std::string(kName); }
  StorageReport storage() const override;
  double flops_per_relight() const override;
  /// rho for float16 and u8; 0 for float32, whose only difference from T is float rounding of
  /// c / s^2, which the relight's float accumulation has anyway.
  double declared_error_bound() const override;
  std::optional<double> expected_frobenius_error() const override { return q_.frobenius_error; }
  LightCoeffs project_light(const Cubemap& radiance) const override;
  void relight(const LightCoeffs& light, LocalRadiance& out) const override;
  /// Relights the listed vertices' rows only (no cube-face skipping).
  bool supports_vertex_subset() const override { return true; }
  void relight_vertices(const LightCoeffs& light, std::span<const std::uint32_t> vertices,
                        LocalRadiance& out) const override;
  std::unique_ptr<DeviceRelighter> upload(ClContext& context,
                                          const ParamSet& device_options) const override;
  void save(ArchiveWriter& archive) const override;

 private:
  QuantizedCsr q_;
};

/// The arrays resident on `context`'s device. The context must outlive the relighter.
std::unique_ptr<DeviceRelighter> upload_quantized(ClContext& context, const QuantizedCsr& arrays);

/// The registry entry (registered by csr_quantized.cpp).
CompressorEntry registry_entry();

}  // namespace prt::csr_quantized
