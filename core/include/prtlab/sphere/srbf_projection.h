#pragma once
// Projection of functions on the sphere onto a fixed set of SRBFs by regularised least squares
// (Tsai and Shih 2006, sections 4.1 and 5.1): the transfer rows of the srbf-cta backend and the
// uniform-SRBF light. For f given on the cube map's pixels (f_k on pixel k, as a row of T is), the
// coefficients c minimise integral (f - sum_j c_j G_j)^2 + alpha |c|^2:
//
//   (A + alpha I) c = b,   A_ij = integral G_i G_j (the closed form, srbf.h),
//                          b_j = sum_k f_k G_j(d_k) Omega_k (the pixel midpoint rule),
//
// with alpha = ridge x max A_ii. The system is factored once (LDLT) for every row projected; its
// condition number (the extreme eigenvalues of A + alpha I) is reported.
//
// Also the interpolation matrix of eq. 13 between two SRBF sets, (A_x)_mn = integral G_m H_n.
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "prtlab/base/types.h"
#include "prtlab/sphere/cubemap.h"
#include "prtlab/sphere/srbf.h"

namespace prt {

struct SrbfBasis {
  SrbfKernel kernel = SrbfKernel::kGaussian;
  std::vector<Vec3d> centres;
  std::vector<double> bandwidths;  ///< one per centre
  std::size_t size() const { return centres.size(); }
};

/// A_ij = integral over S^2 of G_i G_j for two bases of the same kernel (rows: `a`, columns: `b`):
/// the Gram matrix when a = b, eq. 13's interpolation matrix otherwise. ParameterError for
/// different kernels or mismatched bandwidth counts.
Eigen::MatrixXd srbf_inner_products(const SrbfBasis& a, const SrbfBasis& b);

class SrbfProjector {
 public:
  SrbfProjector(SrbfBasis basis, const CubemapLayout& layout, double ridge);

  const SrbfBasis& basis() const { return basis_; }
  double ridge() const { return ridge_; }
  /// alpha = ridge x the largest Gram diagonal entry.
  double alpha() const { return alpha_; }
  /// Largest over smallest eigenvalue of A + alpha I.
  double condition_number() const { return condition_; }
  /// Of A alone (before the ridge); infinite when A is singular to rounding.
  double gram_condition_number() const { return gram_condition_; }

  /// c for f given at every pixel (size N).
  Eigen::VectorXd project(std::span<const double> pixel_values) const;
  /// c for a sparse f: the listed pixels with their values, every other pixel 0 (a row of T).
  Eigen::VectorXd project_sparse(std::span<const std::uint32_t> pixels,
                                 std::span<const double> values) const;
  /// (A + alpha I)^-1 b for many right-hand sides at once (n x k), the coefficients of k
  /// functions whose b vectors the caller accumulated (a block of T's rows).
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const;
  /// b's weights: G_j(d_k) Omega_k, pixel-major (N x n).
  const Eigen::MatrixXd& pixel_weights() const { return weights_; }

 private:
  SrbfBasis basis_;
  double ridge_ = 0, alpha_ = 0, condition_ = 0, gram_condition_ = 0;
  Eigen::MatrixXd weights_;  // N x n
  Eigen::LDLT<Eigen::MatrixXd> solver_;
};

}  // namespace prt
