#pragma once
// Homomorphic factorisation of one ABRDF channel into f(d, e) ~ P(d) Q(h) R(e) (McCool et al.
// 2001, as Suykens et al. 2003 section 4.3 apply it; README.md "Algorithm"): in logarithms the
// product is a sum, log f(s) = p(d_s) + sum_a w_sa q_a + r(e_s), one linear equation per sample
// s with the halfway weights w shading uses, plus lambda times the grid Laplacian of each factor
// (the smoothness regulariser) and two rows fixing the mean of q and of r (the product is
// unchanged by constants that sum to zero). The system depends only on the sampling, so its
// normal matrix is factorised once (sparse Cholesky, LDL^T) and every texel and channel is a
// back-substitution. Samples below `floor` times the channel's maximum are raised to it before
// the logarithm (a BTF's shadowed zeros have no logarithm). Optionally (refine > 0, not in the
// paper) the log fit then starts Gauss-Newton iterations on the same model in linear terms,
// sum_s (exp(model_s) - f_s)^2 plus mean_s(f_s^2) times the squares of the same regulariser rows
// on the log factors, each step halved until that objective decreases.
#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <span>

namespace prt::hf {

struct HomomorphicOptions {
  int light_side = 0, view_side = 0;
  int half_side = 0;
  double lambda = 0.1;
  double floor = 1e-3;
  int refine = 0;  ///< Gauss-Newton iterations in linear terms after the log fit
};

class HomomorphicFactorization {
 public:
  explicit HomomorphicFactorization(const HomomorphicOptions& options);
  int light_count() const { return o_.light_side * o_.light_side; }
  int view_count() const { return o_.view_side * o_.view_side; }
  int half_count() const { return o_.half_side * o_.half_side; }

  /// As cmf::ChainedFactorization::factor. Thread-safe.
  void factor(std::span<const double> f, std::span<double> p, std::span<double> q,
              std::span<double> r) const;
  /// The same in logarithms: x = (log p, log q, log r) for the samples' logarithms `y`.
  void solve_log(std::span<const double> y, std::span<double> x) const;
  /// Up to `iterations` Gauss-Newton steps from the log factors x on the linear objective
  /// (the file comment) against the samples f; returns that objective at the end (it never
  /// exceeds the one at the start).
  double refine_linear(std::span<const double> f, std::span<double> x, int iterations) const;
  /// The linear objective of the log factors x against f.
  double linear_objective(std::span<const double> f, std::span<const double> x) const;

 private:
  HomomorphicOptions o_;
  Eigen::SparseMatrix<double, Eigen::RowMajor> data_rows_;  // (M V) x (M + H + V)
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver_;
  Eigen::SparseMatrix<double> regulariser_;  // the Laplacian and mean rows, x n
  Eigen::MatrixXd regulariser_normal_;       // its R^T R, dense (n is small)
};

}  // namespace prt::hf
