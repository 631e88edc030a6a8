#pragma once
// Backend `cpca_sh`: clustered PCA of the per-vertex SH transfer matrices (Sloan et al. 2003,
// sections 3.2, 3.3 and 6; compressors/cpca_sh/README.md). The signal of vertex p is its
// transfer matrix, rows x n with n = order^2 light coefficients and rows = output_order^2
// local coefficients, flattened row-major:
//
//   zero projection           X_p = M_p[0:rows, 0:n]                (ShTransfer, sh_transfer.h)
//   least-squares projection  X_p = A^-1 M_p[0:rows, 0:n]           (the paper's eq. (1))
//   diffuse signal            t_p = sqrt(4 pi / 3) M_p[2, 0:n]       (1 x n)
//
// The diffuse signal is the paper's 25-D shadowed diffuse transfer vector (its Fig. 2-4),
// t_p[k] = integral of y_k(d) V_p(d) max(d.n, 0) dd: row 2 of M_p is y_{1,0} = sqrt(3 / (4 pi))
// z in the local frame, so the cosine-weighted row is exact in the quadrature of M_p.
//
// with A the hemisphere Gram matrix of output_order (hemisphere_projection.h). Every X_p is
// approximated in the affine subspace of its cluster, X~_p = X_0 + sum_i w_i X_i, so a relight
// is one rows x n matrix-vector product per representative, q_r = X_r l (l: the light's SH
// coefficients), and per vertex a weighted sum of its cluster's q_r: e_p = q_0 + sum_i w_i q_i,
// the local SH coefficients of the transferred radiance (output basis kSphericalHarmonics).
//
// Storage: per vertex the cluster id (u8 / u16 / u32 by cluster count) and its k_c weights (f32,
// IEEE half, or s8 codes times a per-vertex f32 scale); per representative a rows x n f32
// matrix; for the adaptive method the count k_c (u16 per cluster).
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "prtlab/compress/compressor.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/stored_model.h"
#include "prtlab/numeric/clustered_pca.h"

namespace prt::cpca_sh {

inline constexpr std::string_view kName = "cpca_sh";
/// Version of this backend's archive sections and metadata (bumped when they change).
inline constexpr int kStateVersion = 3;
/// The SH order of the transfer the entry asks prepare_scene() for (BackendInputs are static):
/// the `order` parameter takes the leading order^2 x order^2 block of it, which is exactly the
/// transfer of the lower order (both SH index sets are prefixes).
inline constexpr int kInputOrder = 5;

enum class WeightFormat { kFloat32, kFloat16, kS8 };
/// What is clustered per vertex: the transfer matrix X_p, or the diffuse transfer vector t_p.
enum class Signal { kMatrix, kDiffuse };
/// The relight of the diffuse signal returns order-1 SH coefficients of the uniform incident
/// radiance with the same cosine-weighted integral: c_0 = sqrt(4 pi) (t_p . l) / pi, so a
/// Lambertian material shades it as diffuse PRT does. Both relight paths scale the light by it.
inline constexpr double kDiffuseRadianceScale = 1.1283791670955126;  // 2 / sqrt(pi)
enum class Projection { kZero, kLeastSquares };
/// The norm CPCA minimises: kSphere the Euclidean norm of the coefficients (the squared error
/// over the sphere), kHemisphere the squared error over the upper hemisphere, the only part the
/// relight's output is evaluated on: ||A^(1/2) (X~ - X)||_F, A the hemisphere Gram matrix.
enum class Metric { kSphere, kHemisphere };
std::string_view to_string(WeightFormat f);
std::string_view to_string(Projection p);
std::string_view to_string(Metric m);
std::string_view to_string(CpcaMethod m);
std::string_view to_string(Signal s);

/// The arrays both relight paths read.
struct CpcaShArrays {
  std::size_t vertices = 0;
  int order = 0;         ///< of the light: n = order^2 columns
  int output_order = 0;  ///< of the transferred radiance: rows = output_order^2
  Projection projection = Projection::kLeastSquares;
  Metric metric = Metric::kHemisphere;
  CpcaMethod method = CpcaMethod::kIterative;
  WeightFormat format = WeightFormat::kFloat32;
  /// kDiffuse: rows = 1 (output_order 1), projection zero, metric sphere.
  Signal signal = Signal::kMatrix;
  /// Representatives, rep after rep, each a rows x n row-major matrix: cluster c owns reps
  /// first[c] (its mean) to first[c + 1] - 1 (its vectors).
  std::vector<float> reps;
  std::vector<std::uint32_t> first{0};  ///< clusters + 1
  std::vector<std::uint32_t> ids;       ///< vertices: the cluster of each vertex
  /// vertices + 1: vertex p's weights are weight_values[weight_offsets[p] ..]; derived.
  std::vector<std::uint32_t> weight_offsets{0};
  std::vector<float> weights32;          ///< format float32
  std::vector<std::uint16_t> weights16;  ///< format float16: IEEE half bits
  std::vector<std::int8_t> codes;        ///< format s8
  std::vector<float> vertex_scales;      ///< format s8: the value of code 1, per vertex
  /// The weights as the relight multiplies them (decoded halves; s8 codes as floats, the
  /// vertex scale applied after the sum): a cache of the stored weights, not stored itself.
  std::vector<float> weight_values;
  /// ||X~ - X|| / ||X|| over all vertices' signals (the projected SH matrices, not T) in the
  /// metric's norm, of the stored model, computed in double while compressing.
  double signal_error = 0;
  /// M: the local bins the output is evaluated at (to_pixel_basis), for the stored model.
  int local_count = 0;
  /// ||T~ - T||_F / ||T||_F of the stored model read as the pixel-basis transfer
  /// T~_p = B X~_p Y (sh_matrix_model.h), computed in double while compressing.
  double frobenius_error = 0;
  /// sum_p ||X~_p - X_p||^2 and sum_p ||X_p||^2 over all vertices in the metric's norm, of the
  /// stored model (the squared error the paper reports as "total squared error of the signal").
  double signal_squared_error = 0;
  double signal_squared_norm = 0;

  int n() const { return order * order; }
  int rows() const { return output_order * output_order; }
  std::size_t signal_dim() const { return static_cast<std::size_t>(rows()) * n(); }
  std::size_t clusters() const { return first.size() - 1; }
  std::size_t rep_count() const { return first.back(); }
  int vectors_of(std::size_t c) const { return static_cast<int>(first[c + 1] - first[c] - 1); }
  /// Bytes per stored cluster id: 1, 2 or 4.
  std::size_t id_bytes() const;
  /// Every cluster has the same number of vectors (static and iterative), or -1.
  int uniform_vectors() const;
  /// What the relight multiplies the light by: kDiffuseRadianceScale or 1.
  float light_scale() const {
    return signal == Signal::kDiffuse ? static_cast<float>(kDiffuseRadianceScale) : 1.0f;
  }
};

/// Fills weight_offsets and weight_values from ids, first and the stored weights.
void derive_vertex_layout(CpcaShArrays& a);

/// The signals of every vertex (vertices x rows n, row-major, double): the leading rows x n
/// block of each M_p, projected least-squares onto the hemisphere when asked.
std::vector<double> transfer_signals(const ShTransfer& sh, int order, int output_order,
                                     Projection projection);

/// The diffuse signals (vertices x n, double): t_p[k] = sqrt(4 pi / 3) M_p[2][k], k < order^2.
std::vector<double> diffuse_transfer_signals(const ShTransfer& sh, int order);

/// The light as both relight paths multiply it: times light_scale().
std::vector<Rgb> scaled_light(const CpcaShArrays& a, std::span<const Rgb> light);

/// q = X_r l for every representative r (rep_count() x rows RGB values, rep after rep), each
/// entry summed over k in increasing order, as the kernel does.
std::vector<Rgb> representative_products(const CpcaShArrays& a, std::span<const Rgb> light);
/// out[p rows + i] = q[first rows + i] + sum_j w_j q[(first + 1 + j) rows + i] for every vertex
/// (s8: q[...] + scale * sum_j code_j q[...]), TBB over vertices, in the kernel's order.
void blend_vertices(const CpcaShArrays& a, std::span<const Rgb> q, std::span<Rgb> out);
/// The same for the listed vertices only.
void blend_vertex_subset(const CpcaShArrays& a, std::span<const Rgb> q,
                         std::span<const std::uint32_t> vertices, std::span<Rgb> out);

/// X~_p = X_0 + s sum_i w_i X_i of vertex p as stored (s: the s8 scale, else 1), in double, and
/// with `magnitude` |X_0| + |s| sum_i |w_i| |X_i| instead (what bounds the relight's rounding).
void vertex_matrix(const CpcaShArrays& a, std::size_t p, bool magnitude, std::span<double> x);
/// Sets a.local_count and a.frobenius_error (the stored model against T) from the input.
void declare_model_error(CpcaShArrays& a, const TransferInput& input);

class CpcaShTransfer final : public CompressedTransfer, public StoredModel {
 public:
  explicit CpcaShTransfer(CpcaShArrays arrays) : a_(std::move(arrays)) {}
  static std::unique_ptr<CompressedTransfer> load(const ArchiveReader& archive);

  const CpcaShArrays& arrays() const { return a_; }
  /// "sh<order>": the basis of project_light().
  std::string light_basis() const;

  std::string backend() const override { return std::string(kName); }
  StorageReport storage() const override;
  /// Per channel, as the paper counts it: 2 rows n per representative (its product with l)
  /// plus 2 k_c rows per vertex (its blend; s8 adds rows multiplies for the scale).
  double flops_per_relight() const override;
  /// No guarantee for T L: the fit minimises the squared error of the SH matrices, and the SH
  /// truncation of light and transferred radiance is not bounded.
  double declared_error_bound() const override { return kNoErrorBound; }
  /// Of the stored model against T at the bins (not the signal error the fit minimises): the SH
  /// truncation of light and output and the CPCA of the matrices together.
  std::optional<double> expected_frobenius_error() const override { return a_.frobenius_error; }
  /// B X~_p (Y L) in double per vertex, X~_p rebuilt from the stored factors.
  ModelRadiance model_radiance(const Cubemap& radiance) const override;
  RadianceBasis output_basis() const override { return RadianceBasis::kSphericalHarmonics; }
  /// signal_squared_error, signal_squared_norm and signal_relative_error of the stored model,
  /// and cost_model_floats, the paper's storage cost (section 4.1).
  std::vector<BackendMetric> backend_metrics() const override;
  LightCoeffs project_light(const Cubemap& radiance) const override;
  void relight(const LightCoeffs& light, LocalRadiance& out) const override;
  bool supports_vertex_subset() const override { return true; }
  void relight_vertices(const LightCoeffs& light, std::span<const std::uint32_t> vertices,
                        LocalRadiance& out) const override;
  std::unique_ptr<DeviceRelighter> upload(ClContext& context,
                                          const ParamSet& device_options) const override;
  void save(ArchiveWriter& archive) const override;

 private:
  void check_light(const LightCoeffs& light) const;
  void shape_output(LocalRadiance& out) const;

  CpcaShArrays a_;
};

/// The arrays resident on `context`'s device. The context must outlive the relighter.
std::unique_ptr<DeviceRelighter> upload_cpca_sh(ClContext& context, const CpcaShArrays& arrays,
                                                const std::string& light_basis);

/// A^(1/2) (inverse: A^(-1/2)) for the hemisphere Gram matrix A of `order`, symmetric, from A's
/// eigendecomposition (condition number 1.5e5 at order 5: relative accuracy ~1e-11).
Eigen::MatrixXd hemisphere_gram_root(int order, bool inverse);

/// The model of clustered_pca() (points = the signals, multiplied by A^(1/2) from the left for
/// the hemisphere metric) as stored: f32 representatives of X (A^(-1/2) applied back) and
/// weights in `format`, with the stored model's relative error against the points.
CpcaShArrays encode(const ClusteredPca& model, const RowSet& points, CpcaShArrays shape);

CompressorEntry registry_entry();

}  // namespace prt::cpca_sh
