#pragma once
// The least-squares projection onto real spherical harmonics (spherical_harmonics.h) of a
// function known only on the upper hemisphere H (z >= 0), and the error analysis of the
// cheaper hemispherical projections it replaces: Sloan, Hall, Hart and Snyder 2003, "Clustered
// Principal Components for Precomputed Radiance Transfer", section 3.2 and appendix 9. The
// derivations are in docs/hemisphere-projection.md.
//
// A_ik = integral over H of y_i y_k, the Gram matrix of the basis restricted to H. For f on H,
// the zero-hemisphere projection b_k = integral over H of f y_k treats f as zero below the
// horizon; c = A^-1 b minimises the integral over H of (f - sum_i c_i y_i)^2 and so reproduces
// every band-limited f exactly on H.
//
// Structure used throughout: y_lm = T_l^|m|(z) Phi_m(phi) with Phi_m = cos(m phi), 1 or
// sin(|m| phi), so the phi integral makes A block diagonal (A_ik = 0 unless m = m'), the blocks
// of m and -m are equal, and a block is
//   A_(l,m),(l',m) = w_m integral_0^1 T_l^|m|(z) T_l'^|m|(z) dz,  w_m = 2 pi (m = 0) or pi,
// a polynomial integral of degree l + l'. By the parity P_l^m(-z) = (-1)^(l+m) P_l^m(z), an
// entry with l + l' even is half the full-sphere value: A_ii = 1/2, A_ik = 0 for l != l'.
//
// A is nearly singular from order 4 on: its smallest eigenvalue is 1.7e-4 at order 4, 6.6e-6 at
// order 5 and 3.2e-13 at order 10 (one combination of the basis functions, mostly the l = 1,
// m = 0 function, nearly vanishes on H). Everything here is therefore computed from the square
// root of each block, A_m = F_m^T F_m with F_m (z nodes x basis functions) the quadrature-weighted
// values sqrt(w_m W_j) T_l^|m|(z_j) at Gauss-Legendre nodes z_j: singular values and vectors of F_m
// (never eigenvalues of the formed A) give A's small eigenvalues to a relative accuracy of about
// 1e-16 / sqrt(lambda), not 1e-16 / lambda, and QR of F_m gives the Schur complements.
#include <Eigen/Core>
#include <functional>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "prtlab/base/types.h"
#include "prtlab/sphere/sphere_quadrature.h"

namespace prt {

// ---------------------------------------------------------------------------------------------
// The Gram matrix, three independent ways.

/// Exact Gram matrix over the zone z in [z_min, z_max] (-1 <= z_min < z_max <= 1): the phi
/// integral analytically, the z integral by Gauss-Legendre with `order` nodes (exact for the
/// degree <= 2 order - 2 integrands), the z-parts T_l^m from sh_eval at phi = 0. Entries with
/// m != m' are exactly 0. The whole sphere (-1, 1) gives the identity to rounding. n x n with
/// n = order^2; throws ParameterError unless 1 <= order <= kMaxShOrder.
Eigen::MatrixXd sh_zone_gram(int order, double z_min, double z_max);
/// sh_zone_gram(order, 0, 1): A.
Eigen::MatrixXd hemisphere_gram(int order);

/// The same matrix in closed form, independent of sh_eval: the associated Legendre functions'
/// polynomial coefficients from Rodrigues' formula (exact integers), multiplied and integrated
/// term by term (integral of z^k over [a, b] = (b^(k+1) - a^(k+1)) / (k + 1)) in long double,
/// then rounded to double. The monomial sums cancel: agreement with sh_zone_gram is about 1e-15
/// at order 10 on [0, 1] (long double, 64-bit mantissa).
Eigen::MatrixXd sh_zone_gram_closed_form(int order, double z_min, double z_max);

/// Quadrature Gram matrix sum_j w_j y(d_j) y(d_j)^T over any rule (e.g. zone_midpoint_rule),
/// with sh_eval at every node: an independent check of sh_zone_gram.
Eigen::MatrixXd sh_gram(int order, std::span<const SphereQuadratureNode> nodes);

/// A rigorous entrywise bound on |sh_gram(order, zone_midpoint_rule(z_min, z_max, z_cells, p)) -
/// sh_zone_gram(order, z_min, z_max)| when p > 2 (order - 1) (the phi rule is then exact): the
/// midpoint error h^2 / 24 (z_max - z_min) max|g''| with g the polynomial (degree d <= 2 order - 2)
/// phi integral of y_i y_k, |g''| <= 4 d^2 (d - 1)^2 max|g| / (z_max - z_min)^2 by Markov's
/// inequality twice, and max|g| <= 2 pi (2 order - 1) / (4 pi) by the addition theorem
/// (sum_m y_lm^2 = (2l + 1) / (4 pi)). Loose (the true error is ~ h^2 / 24 |g'(1) - g'(0)|)
/// but derived.
double sh_gram_midpoint_error_bound(int order, double z_min, double z_max, int z_cells);

/// b_k = sum_j w_j f(d_j) y_k(d_j) over a rule: the projection of f onto order^2 functions.
/// Over zone_gauss_rule(0, 1, ...) this is the zero-hemisphere projection of f, exact for a
/// band-limited f when the rule is exact (see sphere_quadrature.h).
Eigen::VectorXd sh_quadrature_projection(int order, std::span<const SphereQuadratureNode> nodes,
                                         const std::function<double(const Vec3d&)>& f);

// ---------------------------------------------------------------------------------------------
// The least-squares projection c = A^-1 b.

struct HemisphereProjectorOptions {
  /// Eigen-directions of A (of the kept basis) with eigenvalue <= relative_cutoff * lambda_max
  /// are left out: the result is then the minimum-norm least-squares solution, the
  /// pseudo-inverse A^+ b. The default 1e-14 is at the rounding level of b in double and below
  /// A's smallest eigenvalue at every order <= 10 (3.2e-13 at order 10), so by default the solve
  /// is the exact inverse. Raise it (e.g. to the relative noise of b) when b is noisy: see the
  /// guarantee on HemisphereProjector. Must be in [0, 1).
  double relative_cutoff = 1e-14;
  /// An SH index to leave out of the basis (its coefficient is 0 and b's entry unused), or -1.
  /// The paper leaves out sh_index(1, 0), the function best approximated on H by the others
  /// (hemisphere_discard_errors): this improves the conditioning (lambda_min 6.6e-6 -> ~3e-4 at
  /// order 5) for an exactly known squared error c_i^2 e_i on a band-limited f.
  int dropped_index = -1;
};

/// c = A^+ b per block: A_m = V S^2 V^T from the SVD of the block's square root F_m, then
/// c_m = V S^-2 V^T b_m over the kept singular values.
///
/// Guarantee, for b = A c + delta with c any coefficient vector of this order (delta: the error
/// of b, e.g. quadrature rounding or noise), writing lambda_j, v_j for the eigenpairs of A and
/// ||x||_A^2 = x^T A x = integral over H of (sum x_i y_i)^2:
///   ||c' - c||_A^2 = sum_{cut j} lambda_j (v_j . c)^2 + sum_{kept j} (v_j . delta)^2 / lambda_j,
/// so the RMS error over H is <= sqrt(lambda_cut_max) ||c|| + ||delta|| / sqrt(lambda_kept_min),
/// and ||c'|| <= ||b|| / lambda_kept_min. With nothing cut, ||c' - c|| <= ||delta|| /
/// lambda_min plus the solve's own rounding, about n eps (lambda_max / lambda_min) ||c||.
/// With dropped_index = i the same holds with A, c replaced by the reduced basis; for b = A c
/// the result is the best approximation of f on H by the other functions, of squared error
/// c_i^2 e_i exactly (e_i = hemisphere_discard_errors(order)[i]).
class HemisphereProjector {
 public:
  /// Throws ParameterError for an order outside [1, kMaxShOrder], a cutoff outside [0, 1) or a
  /// dropped index outside [-1, order^2).
  explicit HemisphereProjector(int order, const HemisphereProjectorOptions& options = {});

  int order() const { return order_; }
  int size() const { return order_ * order_; }
  /// c' from the zero-hemisphere projection b (size order^2; throws ParameterError otherwise).
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;

  double largest_eigenvalue() const { return lambda_max_; }
  /// The smallest eigenvalue of the (reduced) A that the solve inverts.
  double smallest_kept_eigenvalue() const { return lambda_kept_min_; }
  /// The largest eigenvalue left out, 0 when none is.
  double largest_cut_eigenvalue() const { return lambda_cut_max_; }
  int cut_directions() const { return cut_; }

 private:
  struct Block {
    std::vector<int> indices;             ///< SH indices of the block's (kept) basis functions
    Eigen::MatrixXd vectors;              ///< kept right singular vectors of F_m, one per column
    Eigen::VectorXd inverse_eigenvalues;  ///< 1 / s_j^2 for the kept columns
  };
  int order_ = 0;
  std::vector<Block> blocks_;
  double lambda_max_ = 0.0, lambda_kept_min_ = 0.0, lambda_cut_max_ = 0.0;
  int cut_ = 0;
};

// ---------------------------------------------------------------------------------------------
// Spectrum and redundancy of the basis on H.

/// Eigenvalues of A (= its singular values: A is symmetric positive definite), decreasing,
/// squares of the blocks' singular values (each m != 0 value twice, once for m and once for -m).
Eigen::VectorXd hemisphere_gram_eigenvalues(int order);

/// Per SH index i: the squared error over H of the best approximation of y_i by the other
/// order^2 - 1 functions, min_a integral_H (y_i - sum_{k != i} a_k y_k)^2 = the Schur complement
/// A_ii - A_i,-i A_-i,-i^-1 A_-i,i = 1 / (A^-1)_ii. Computed stably as R_nn^2 from a Householder QR
/// of the block's square root F_m with column i moved last (no inverse of A is formed).
Eigen::VectorXd hemisphere_discard_errors(int order);

// ---------------------------------------------------------------------------------------------
// Error analysis of the hemispherical projections (appendix 9.2).

enum class HemisphereProjectionKind {
  /// b = A c at the projection order: f taken as zero below the horizon (E1, Q1 when the
  /// projection order is the signal order).
  kZeroHemisphere,
  /// The SH projection of f_odd(x, y, z) = f(x, y, z) for z >= 0, -f(x, y, -z) otherwise: 2 b_k
  /// for the functions odd in z (y(x, y, -z) = -y(x, y, z), l + m odd), 0 for the others (E2).
  kOddReflection,
  /// The same for f_even(x, y, z) = f(x, y, -z) below the horizon: 2 b_k for the functions even
  /// in z (l + m even), 0 for the others.
  kEvenReflection,
};
/// "zero_hemisphere", "odd_reflection", "even_reflection".
std::string_view to_string(HemisphereProjectionKind kind);

/// D*: the factor each of the order^2 zero-hemisphere coefficients gets (1 for kZeroHemisphere;
/// 2 or 0 by the parity l + m for the reflections).
Eigen::VectorXd reflection_scale(HemisphereProjectionKind kind, int order);

/// Q, n x n with n = signal_order^2: for every f = sum_i c_i y_i of signal_order, the squared
/// error over H of the projection at projection_order M >= signal_order is c^T Q c. Q is the
/// upper-left n x n block of (D* A - I)^T A (D* A - I), A and D* of order M (c padded with
/// zeros to M^2). Throws ParameterError unless 1 <= signal_order <= M <= kMaxShOrder.
Eigen::MatrixXd hemisphere_projection_error_matrix(HemisphereProjectionKind kind, int signal_order,
                                                   int projection_order);

struct HemisphereProjectionError {
  HemisphereProjectionKind kind = HemisphereProjectionKind::kZeroHemisphere;
  int signal_order = 0;
  int projection_order = 0;
  int coefficients = 0;  ///< projection coefficients that can be non-zero: M^2, or D*'s non-zeros
  /// max of c^T Q c over unit c (||c|| = 1: unit squared integral over the sphere): Q's largest
  /// eigenvalue.
  double worst = 0.0;
  /// mean of c^T Q c over c uniform on the unit sphere: trace(Q) / n, Q's mean eigenvalue.
  double average = 0.0;
  double worst_rms_percent() const;    ///< 100 sqrt(worst)
  double average_rms_percent() const;  ///< 100 sqrt(average)
};
HemisphereProjectionError hemisphere_projection_error(HemisphereProjectionKind kind,
                                                      int signal_order, int projection_order);

/// The paper's projection orders: odd reflection at order 8 (28 non-zero coefficients of 64),
/// even reflection at order 7 (28 of 49); both at least the signal order.
inline constexpr int kPaperOddReflectionOrder = 8;
inline constexpr int kPaperEvenReflectionOrder = 7;

struct HemisphereAnalysisOptions {
  /// nullopt: the paper's order, raised to the signal order when below it. A value below the
  /// signal order is a ParameterError.
  std::optional<int> odd_order;
  std::optional<int> even_order;
};

/// Everything `prtlab sh hemisphere` reports for one order.
struct HemisphereAnalysis {
  int order = 0;
  Eigen::VectorXd eigenvalues;    ///< hemisphere_gram_eigenvalues(order)
  Eigen::VectorXd discard_error;  ///< hemisphere_discard_errors(order)
  int most_redundant = 0;         ///< argmin of discard_error (an SH index)
  /// zero-hemisphere at the order, odd reflection at the odd order, even reflection at the even
  /// order, even reflection at the order: in this order.
  std::vector<HemisphereProjectionError> projections;
};
HemisphereAnalysis analyse_hemisphere_projection(int order,
                                                 const HemisphereAnalysisOptions& options = {});

}  // namespace prt
