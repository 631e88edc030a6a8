#pragma once
// Backend `haar`: non-linear approximation of T's rows in the 2D non-standard Haar basis of each
// cube face (Ng, Ramamoorthi, Hanrahan 2003), as the central paper's Fig. 6 uses it: every row
// is transformed once, and the k coefficients of largest area-weighted magnitude
// |c| x (solid angle of the basis function's support) are kept (compressors/haar/README.md).
//
//   T~[row] = sum over the kept j of c_j psi_j        relight: (T~ L)_row = sum_j c_j (W L)_j
//
// The light is transformed once per relight (W L, haar_wavelet.h); each row is then a sparse dot
// product of its kept terms with it.
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "haar/haar_light.h"
#include "prtlab/compress/compressor.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/stored_model.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt::haar {

inline constexpr std::string_view kName = "haar";
/// Version of this backend's archive sections and metadata (bumped when they change).
inline constexpr int kStateVersion = 1;

enum class ValueFormat { kFloat32, kFloat16, kS8 };
std::string_view to_string(ValueFormat f);
/// How the kept terms are chosen.
enum class Budget {
  kPerRow,  ///< the paper: k terms in every row (fewer where a row has fewer non-zero ones)
  kGlobal,  ///< k x rows terms over the whole matrix, by the same score, at most max_terms a row
};
std::string_view to_string(Budget b);
/// What happens to each face's scaling coefficient (the face average).
enum class Scaling {
  kRanked,  ///< ranked like every other coefficient (its support is the whole face)
  kAlways,  ///< kept whenever non-zero, counted in the row's terms
};
std::string_view to_string(Scaling s);

struct HaarOptions {
  int k = 12;  ///< terms per row (per-row budget) or the mean per row (global budget)
  ValueFormat format = ValueFormat::kS8;
  bool wide_index = false;  ///< u32 indices even where u16 would do (u32 is forced for N > 65536)
  Budget budget = Budget::kPerRow;
  Scaling scaling = Scaling::kRanked;
  int max_terms = 0;  ///< global budget: most terms per row; 0: 8 k (and at most N)
};

/// The kept terms of every row: the arrays both relight paths read.
struct HaarArrays {
  std::size_t vertices = 0;
  int local_count = 0;  ///< M
  int pixel_count = 0;  ///< N
  int resolution = 0;   ///< R (N = 6 R^2), a power of two
  ValueFormat format = ValueFormat::kS8;
  Budget budget = Budget::kPerRow;
  Scaling scaling = Scaling::kRanked;
  int k = 0;
  bool wide = false;                      ///< u32 indices (else u16)
  std::vector<std::uint32_t> offsets{0};  ///< rows + 1, from the stored per-row counts
  std::vector<std::uint16_t> indices16;   ///< terms: coefficient index k (cubemap order), rising
  std::vector<std::uint32_t> indices32;   ///< the same, when wide
  std::vector<float> values32;            ///< terms, format float32
  std::vector<std::uint16_t> values16;    ///< terms, format float16 (IEEE half bits)
  std::vector<std::int8_t> codes;         ///< terms, format s8: value = code x the row's scale
  std::vector<float> row_scales;          ///< rows, format s8: max |c| / 127 of the row's terms
  /// Squared errors in double, over the whole matrix: dropped coefficients, the quantisation of
  /// the kept ones, and ||T||_F^2. By Parseval they add up to ||T~ - T||_F^2.
  double truncation_squared_error = 0;
  double quantization_squared_error = 0;
  double total_squared_norm = 0;

  std::size_t rows() const { return offsets.size() - 1; }
  std::size_t terms() const { return offsets.back(); }
  std::uint32_t count(std::size_t row) const { return offsets[row + 1] - offsets[row]; }
  std::size_t index_bytes() const { return wide ? 4 : 2; }
  std::size_t value_bytes() const;
  /// Bytes per stored row count: 1, 2 or 4, the narrowest that holds the largest count.
  std::size_t count_bytes() const;
  /// ||T~ - T||_F / ||T||_F (0 for an all-zero T).
  double frobenius_error() const;
};

/// Transforms every row of T, keeps its terms under `options` and quantises them. Throws
/// ParameterError unless R is a power of two.
HaarArrays encode_haar(const TransferMatrix& t, const CubemapLayout& cubemap,
                       const HaarOptions& options, Progress& progress);

/// W L per colour channel, float (the C++ reference of the kernel haar_light).
std::vector<Rgb> transform_light(std::span<const Rgb> light, int resolution);
/// out = T~ light for a pixel-basis light (transformed here; TBB over rows; four accumulators
/// per row, summed as the kernel sums).
void relight_haar(const HaarArrays& a, std::span<const Rgb> light, std::span<Rgb> out);
/// The rows of `vertices` (sorted, unique, checked by the caller) with relight_haar's bits;
/// other rows of out are not written.
void relight_haar_vertices(const HaarArrays& a, std::span<const Rgb> light,
                           std::span<const std::uint32_t> vertices, std::span<Rgb> out);
/// Whether `light` is a wavelet-basis light (kLightBasis); ParameterError unless it is that or a
/// pixel light, of `pixels` values.
bool check_light(const LightCoeffs& light, std::size_t pixels);
/// out = T~ L for a light given as its Haar coefficients (W L, or the truncation of it that
/// approximate_light makes: haar_light.h), with relight_haar's row sums.
void relight_haar_wavelet(const HaarArrays& a, std::span<const Rgb> coefficients,
                          std::span<Rgb> out);
void relight_haar_wavelet_vertices(const HaarArrays& a, std::span<const Rgb> coefficients,
                                   std::span<const std::uint32_t> vertices, std::span<Rgb> out);

class HaarTransfer final : public CompressedTransfer, public StoredModel {
 public:
  explicit HaarTransfer(HaarArrays arrays) : a_(std::move(arrays)) {}
  /// The state written by save() (InputError naming the file when it is inconsistent).
  static std::unique_ptr<CompressedTransfer> load(const ArchiveReader& archive);

  const HaarArrays& arrays() const { return a_; }

  std::string backend() const override { return std::string(kName); }
  StorageReport storage() const override;
  /// The light's fast transform plus 2 per kept term (a multiply-add) plus, for s8, one multiply
  /// per row by its scale.
  double flops_per_relight() const override;
  /// None: dropping terms bounds ||T~ - T||_F, not ||T~ L - T L|| / ||T L||.
  double declared_error_bound() const override { return kNoErrorBound; }
  std::optional<double> expected_frobenius_error() const override { return a_.frobenius_error(); }
  /// Every row's kept terms (decoded, double) inverse-transformed to the pixel basis and dotted
  /// with L; the magnitude sums |c_j| times |psi_j| |L| over the terms.
  ModelRadiance model_radiance(const Cubemap& radiance) const override;
  /// The pixel-basis light: the Haar transform is part of every relight (C++ and OpenCL).
  LightCoeffs project_light(const Cubemap& radiance) const override;
  /// Ng 2003's run-time approximation of the light: its Haar coefficients, only the best
  /// `approximation.terms` kept (haar_light.h), as a light in the wavelet basis (kLightBasis).
  /// The archive does not depend on it; with every term the relight has project_light's bits.
  LightCoeffs project_light(const Cubemap& radiance, const LightApproximation& approximation) const;
  /// The registry's light options: light_terms (N; 0 = every term) and light_weight.
  LightCoeffs project_light_under(const Cubemap& radiance,
                                  const ParamSet& light_options) const override;
  /// A pixel light (transformed here) or a wavelet-basis light (multiplied as it is).
  void relight(const LightCoeffs& light, LocalRadiance& out) const override;
  bool supports_vertex_subset() const override { return true; }
  void relight_vertices(const LightCoeffs& light, std::span<const std::uint32_t> vertices,
                        LocalRadiance& out) const override;
  std::unique_ptr<DeviceRelighter> upload(ClContext& context,
                                          const ParamSet& device_options) const override;
  void save(ArchiveWriter& archive) const override;

 private:
  HaarArrays a_;
};

/// The device's product order (device option opencl_order): the same result up to float
/// rounding either way.
enum class DeviceOrder {
  kRows,     ///< one work-item per row over its stored terms (every term, whatever the light)
  kColumns,  ///< Ng 2003's order: only the columns of the light's non-zero terms (haar_columns.h)
};
/// The arrays resident on `context`'s device. The context must outlive the relighter.
std::unique_ptr<DeviceRelighter> upload_haar(ClContext& context, const HaarArrays& arrays,
                                             DeviceOrder order = DeviceOrder::kRows);

/// The registry entry (registered by haar.cpp).
CompressorEntry registry_entry();

}  // namespace prt::haar
