#pragma once
// Chained matrix factorisation of one ABRDF channel into f(d, e) ~ P(d) Q(h) R(e) (Suykens et
// al. 2003, section 4.2; README.md "Algorithm"):
//   1. resample the M x V in/out samples to the GSHD parameterisation (halfway x difference
//      cells, halfway_parameterization.h);
//   2. the halfway factor Q from that matrix: the mean over the valid difference samples of
//      each halfway row (the paper's three-factor rule, `halfway = mean`) or its rank-1
//      approximation over the valid entries with the difference factor averaged out
//      (`halfway = svd`). Or, skipping the resampling (`halfway = project`, not in the paper),
//      the projection of the samples themselves onto the halfway grid: Q_a = sum_s w_sa f_s /
//      sum_s w_sa with the halfway weights shading uses. The resampling interpolates the
//      incident and exitant directions separately on their grids, which smears a highlight
//      narrower than a grid cell over its neighbours; the projection puts every sample at its
//      own halfway direction;
//   3. divide the in/out samples by Q read back at each pair's halfway direction (the weights
//      shading uses) and take the rank-1 SVD of the residue: P and R;
//   4. optionally (`refine` > 0, not in the paper) alternate least squares on the final model
//      in the original samples: Q by a sparse normal-equation solve (pulled weakly towards its
//      previous value and clamped at 0), then P and R in closed form (each the exact minimiser
//      with the others fixed).
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <span>
#include <string>

#include "prtlab/btf/halfway_parameterization.h"

namespace prt::cmf {

enum class HalfwayRule { kMean, kSvd, kProject };

struct ChainOptions {
  int light_side = 0, view_side = 0;
  int half_side = 0;  ///< Q's grid
  int diff_side = 0;  ///< GSHD difference grid of step 1
  HalfwayRule halfway = HalfwayRule::kSvd;
  int refine = 0;
};

/// The sampling-dependent parts of the chain, shared by every texel and channel.
class ChainedFactorization {
 public:
  explicit ChainedFactorization(const ChainOptions& options);
  const ChainOptions& options() const { return o_; }
  int light_count() const { return o_.light_side * o_.light_side; }
  int view_count() const { return o_.view_side * o_.view_side; }
  int half_count() const { return o_.half_side * o_.half_side; }

  /// Factors one channel: f holds M V samples (s = view * M + light), all >= 0; p (M), q (H)
  /// and r (V) receive non-negative factors. Thread-safe.
  void factor(std::span<const double> f, std::span<double> p, std::span<double> q,
              std::span<double> r) const;

 private:
  void halfway_from_gshd(const Eigen::Ref<const Eigen::VectorXd>& f, std::span<double> q) const;
  void divide_and_split(std::span<const double> f, std::span<double> p, std::span<double> q,
                        std::span<double> r) const;
  void refine(std::span<const double> f, std::span<double> p, std::span<double> q,
              std::span<double> r) const;
  ChainOptions o_;
  GshdResampling gshd_;
  Eigen::SparseMatrix<double, Eigen::RowMajor> w_;   // halfway weights, (M V) x H
  Eigen::SparseMatrix<double, Eigen::RowMajor> wt_;  // its transpose
  Eigen::VectorXd w_colsum_;
  // The lower triangle of W^T W (the pattern of Q's normal matrix) and, per sample, where the
  // products of its weights land in its value array.
  Eigen::SparseMatrix<double> normal_pattern_;
  std::vector<int> sample_begin_;
  std::vector<int> sample_slot_;
};

/// Rank-1 approximation u v^T of a rows x cols column-major non-negative matrix by power
/// iteration from the column means (the Perron vectors, so u, v >= 0); u and v share the
/// singular value as sqrt(sigma) each.
void rank_one(std::span<const double> a, int rows, int cols, std::span<double> u,
              std::span<double> v);

}  // namespace prt::cmf
