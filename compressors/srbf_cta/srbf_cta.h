#pragma once
// Backend `srbf_cta`: transfer in spherical radial basis functions compressed by clustered tensor
// approximation (Tsai and Shih 2006; compressors/srbf_cta/README.md). Every row of T (a function
// over the light sphere) is projected onto n_t uniform Gaussian SRBFs; a vertex's M rows make an
// M x n_t matrix, all of them a tensor (local direction x SRBF x vertex), which
// clustered_tensor.h approximates with a shared view basis U (M x R1), per cluster a light basis
// U_c (n_t x R2) and a dual vertex basis V_c (R3 x R1 R2), and per vertex R3 weights W_x.
//
// Relight (the paper's section 6, the view step folded into the cluster step because our output
// is the M local directions themselves):
//   light  L' = the light's inner products with the transfer SRBFs (project_light: A L for
//             uniform or scattered light SRBFs, or the pixel quadrature)
//   per cluster  L'_c = U_c^T L',  R_c = [refold(V_cj) L'_c]_j  (R1 x R3),  Q_c = U R_c (M x R3)
//   per vertex   L*_x = Q_c W_x  (M values)
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "prtlab/compress/compressor.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/stored_model.h"
#include "prtlab/sphere/srbf_projection.h"

namespace prt::srbf_cta {

inline constexpr std::string_view kName = "srbf_cta";
inline constexpr int kStateVersion = 3;

enum class Precision { kFloat32, kFloat16 };
/// How project_light computes L': the light fitted with uniform SRBFs (eq. 13's interpolation
/// matrix), with scattered SRBFs (section 5.3's fit, then eq. 13), or the pixel quadrature of the
/// inner products directly (the limit of a dense light basis).
enum class LightMode { kUniform, kScattered, kPixel };
/// What the tensor's view mode holds: T's M local cells (the relight is the local radiance L*),
/// or the paper's K BRDF terms of the BRDF-weighted transfer (transfer/brdf_weighted_transfer.h;
/// the relight is then the outgoing radiance B towards the M cells as view directions, with the
/// view functions Phi folded into the stored view basis).
enum class Signal { kCells, kBrdf };

std::string_view to_string(Precision p);
std::string_view to_string(LightMode m);
std::string_view to_string(Signal s);

/// The arrays both relight paths read (decoded floats), and what produced them.
struct SrbfCtaArrays {
  std::size_t vertices = 0;
  int local_count = 0;   ///< M = I1
  int pixel_count = 0;   ///< N
  int srbf_count = 0;    ///< n_t = I2: icosphere centres
  double bandwidth = 0;  ///< of every transfer SRBF (Gaussian)
  double ridge = 0;
  int rank_view = 0, rank_light = 0, rank_vertex = 0;  ///< R1, R2, R3
  Precision precision = Precision::kFloat16;
  LightMode light = LightMode::kUniform;
  int light_srbfs = 0;    ///< n_l (0: the transfer SRBFs)
  int light_rounds = 40;  ///< of the scattered fit
  Signal signal = Signal::kCells;
  int brdf_terms = 0;              ///< K of the BRDF-weighted signal (0 for cells)
  std::vector<float> view_basis;   ///< M x R1 (for the BRDF signal: Phi U_view)
  std::vector<float> light_bases;  ///< clusters x n_t x R2
  std::vector<float> duals;        ///< clusters x R3 x (R1 R2), rows beyond a cluster's rank 0
  std::vector<std::uint32_t> ids;  ///< per vertex
  std::vector<float> weights;      ///< vertices x R3
  /// ||T~ - T||_F / ||T||_F of the stored model with its light step (light_operator()); of the
  /// SRBF projection alone (before CTA, with the pixel quadrature). For the BRDF signal the
  /// reference is the folded transfer Psi T (K terms), equivalently its outgoing radiance F_K T
  /// over the view cells (brdf_weighted_transfer.h).
  double frobenius_error = 0, srbf_frobenius_error = 0;

  std::size_t clusters() const {
    return srbf_count == 0 || rank_light == 0
               ? 0
               : light_bases.size() / (static_cast<std::size_t>(srbf_count) * rank_light);
  }
  std::size_t id_bytes() const;
};

/// The transfer SRBFs: icosphere centres, one Gaussian bandwidth.
SrbfBasis transfer_basis(int srbf_count, double bandwidth);

/// Per cluster R_c and Q_c = U R_c (clusters x M x R3 RGB) for L' (n_t RGB), in the kernels'
/// order of summation.
std::vector<Rgb> cluster_matrices(const SrbfCtaArrays& a, std::span<const Rgb> light);
/// L*_x = Q_c W_x for the listed vertices (all when `vertices` is empty and `all`).
void blend_vertices(const SrbfCtaArrays& a, std::span<const Rgb> q,
                    std::span<const std::uint32_t> vertices, bool all, std::span<Rgb> out);

class SrbfCtaTransfer final : public CompressedTransfer, public StoredModel {
 public:
  /// `projector`: the transfer SRBFs' projector when the caller has it (the compressor), else
  /// built here.
  explicit SrbfCtaTransfer(SrbfCtaArrays arrays,
                           std::shared_ptr<const SrbfProjector> projector = nullptr);
  static std::unique_ptr<CompressedTransfer> load(const ArchiveReader& archive);

  const SrbfCtaArrays& arrays() const { return a_; }
  std::string light_basis() const;

  std::string backend() const override { return std::string(kName); }
  StorageReport storage() const override;
  /// Per channel: the light step's product (2 n_t n_l, or 2 N n_t for the pixel quadrature),
  /// per cluster 2 n_t R2 + 2 R3 R1 R2 + 2 M R1 R3, per vertex 2 M R3.
  double flops_per_relight() const override;
  double declared_error_bound() const override { return kNoErrorBound; }
  /// The stored model's error with the light step it relights through (uniform or pixel); none
  /// for scattered light, whose fit depends on the light non-linearly (no operator T~ exists).
  std::optional<double> expected_frobenius_error() const override {
    return a_.light == LightMode::kScattered ? std::nullopt
                                             : std::optional<double>(a_.frobenius_error);
  }
  /// G (N x n_t): the light step as a pixel-basis operator, L' = G^T L. Pixel: b's weights over
  /// the solid angles; uniform: diag(1 / Omega) W_l (A_l + alpha I)^-1 E^T, the fit to the light
  /// SRBFs and eq. 13 in one matrix; scattered (not linear): the pixel quadrature's.
  Eigen::MatrixXd light_operator() const;
  /// Sets the declared error: the stored model through light_operator() against `t` (the
  /// compressor calls it once, with the T it compressed).
  void declare_model_error(const TransferMatrix& t);
  /// Per vertex U K_x (U_c^T L'), K_x = refold(W_x V_c) rebuilt in double, L' of
  /// light_products().
  ModelRadiance model_radiance(const Cubemap& radiance) const override;
  /// L' (n_t x 3, double): what project_light() rounds to float.
  Eigen::MatrixXd light_products(const Cubemap& radiance) const;
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

  SrbfCtaArrays a_;
  SrbfBasis basis_;
  std::shared_ptr<const SrbfProjector> transfer_projector_;  // pixel weights of the light step
  // Uniform light: its projector and eq. 13's interpolation matrix (n_t x n_l).
  std::shared_ptr<const SrbfProjector> light_projector_;
  Eigen::MatrixXd interpolation_;
};

std::unique_ptr<DeviceRelighter> upload_srbf_cta(ClContext& context, const SrbfCtaArrays& arrays,
                                                 const std::string& light_basis);

CompressorEntry registry_entry();

}  // namespace prt::srbf_cta
