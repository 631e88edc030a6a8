#pragma once
// The BRDF-weighted transfer of Tsai and Shih 2006 (eq. 9) built from the pixel-basis T.
//
// With one BRDF rho everywhere (in the local frame), the outgoing radiance of vertex x towards
// view direction o under light L is B_x(o) = sum_j F[o, j] (T_x L)_j, where (T_x L)_j is the
// radiance arriving through local cell j integrated over the cell (transfer_matrix.h) and
//     F[o, j] = rho(d_j, o) cos(theta_j)
// with d_j cell j's centre and cos(theta_j) the cell-mean cosine. The view directions o are the
// cells of the same hemisphere grid (so B has T's shape: M values per vertex).
//
// The paper factors rho into K separable terms by an SVD; here the factored kernel is F, weighted
// so that the truncation is optimal for the L2 norms over view and light directions:
//     A = sqrt(Omega_o) F sqrt(Omega_j) = U S W^T,
//     view  Phi = U_K / sqrt(Omega_o)            (M x K: phi_k at the view cells)
//     light Psi = S_K W_K^T / sqrt(Omega_j)      (K x M: psi_k x cosine per local cell)
// so that Phi Psi = F_K, the rank-K truncation of F, with
//     ||sqrt(Omega_o) (F - Phi Psi) sqrt(Omega_j)||_F^2 = sum of the dropped sigma_i^2.
// The folded transfer T'_x = Psi T_x (K x N per vertex: the paper's T_x,k sampled at the
// pixels) is the signal whose SRBF and CTA approximations the paper's SE ratios measure;
// Phi T'_x = F_K T_x is its BRDF-weighted transfer. Phi's columns are orthonormal under the
// view-cell weight, so ||Phi Y||^2 Omega_o = ||Y||^2: an error in the K terms is the same
// error in outgoing radiance over the view cells.
#include <Eigen/Core>
#include <cstddef>

#include "prtlab/base/types.h"

namespace prt {

class HemisphereGrid;
class TransferMatrix;

/// Cook-Torrance (Cook and Torrance 1982) in the local frame (normal +z):
///   rho(l, v) = kd / pi + (1 - kd) D(h) F(v . h) G(l, v) / (4 (n . l) (n . v))
/// with the Beckmann distribution D of RMS slope m, Schlick's Fresnel with F0, and the V-cavity
/// masking G = min(1, 2 (n.h)(n.v) / (v.h), 2 (n.h)(n.l) / (v.h)). The paper names the model but
/// not its parameters; these defaults are a glossy dielectric-like lobe.
struct CookTorrance {
  double diffuse = 0.3;    ///< kd: the Lambertian share (the specular share is 1 - kd)
  double roughness = 0.3;  ///< Beckmann m (RMS microfacet slope)
  double fresnel0 = 0.5;   ///< Schlick F0, reflectance at normal incidence
  /// rho(l, v) for unit local directions; 0 when either is at or below the horizon.
  double operator()(const Vec3d& l, const Vec3d& v) const;
  /// ParameterError naming the parameter unless 0 <= kd <= 1, 0 < m <= 10, 0 <= F0 <= 1.
  void validate() const;
};

/// F[o, j] = rho(d_j, d_o) cos(theta_j) over the grid's cells as view (rows) and light
/// (columns) directions, cos(theta_j) the cell-mean cosine (M x M).
Eigen::MatrixXd brdf_cosine_kernel(const HemisphereGrid& grid, const CookTorrance& brdf);

struct BrdfFold {
  int terms = 0;                    ///< K
  Eigen::MatrixXd view;             ///< Phi: M x K
  Eigen::MatrixXd light;            ///< Psi: K x M
  Eigen::VectorXd singular_values;  ///< of A, all M, descending
  double view_weight = 0;           ///< Omega_o, solid angle of a view cell
  double light_weight = 0;          ///< Omega_j, solid angle of a local cell
  /// sum_{i > K} sigma_i^2 / sum_i sigma_i^2: the weighted kernel's share the truncation drops.
  double dropped_fraction() const;
};

/// The K-term factorisation above. ParameterError unless 1 <= terms <= M, or for a bad BRDF.
BrdfFold fold_brdf(const HemisphereGrid& grid, const CookTorrance& brdf, int terms);

/// Psi T_x: vertex x's folded transfer, K x N dense (tests and small scenes).
Eigen::MatrixXd folded_vertex(const TransferMatrix& t, const BrdfFold& fold, std::size_t x);
/// F T_x computed directly (no factorisation): vertex x's BRDF-weighted transfer, M x N dense.
Eigen::MatrixXd brdf_weighted_vertex(const TransferMatrix& t, const Eigen::MatrixXd& kernel,
                                     std::size_t x);
/// sum over vertices of ||Psi T_x||_F^2, from T's stored entries (each column of a vertex block
/// has one entry, so this is sum_e T_e^2 ||Psi[:, j_e]||^2).
double folded_squared_norm(const TransferMatrix& t, const BrdfFold& fold);

}  // namespace prt
