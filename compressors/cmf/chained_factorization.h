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
//      shading uses) and take the rank-1 SVD of the residue: P and R. With `terms` K > 1 (the
//      paper's multiple-term approximation of a step, eq. 3) the residue is split into K
//      non-negative terms sum_k P_k R_k^T instead of the K leading singular pairs, whose
//      factors past the first change sign and could not be stored as the non-negative 8-bit
//      textures (the paper names non-negative factorisation as the alternative). Term k joins
//      the fit of terms 1 .. k-1 as the rank-1 SVD of the positive part of what they leave,
//      followed by sweeps of hierarchical alternating least squares (each P_k, then each R_k,
//      the exact non-negative minimiser with the others fixed), starting from P_k = 0 so that K
//      terms never fit worse than K - 1 (with `refine` > 0, in the original samples after step
//      4 has refined the K - 1 terms, and step 4 runs again on the K);
//   4. optionally (`refine` > 0, not in the paper) alternate least squares on the final model
//      in the original samples: Q by a sparse normal-equation solve (pulled weakly towards its
//      previous value and clamped at 0), then each P_k and R_k in closed form (each the exact
//      non-negative minimiser with the others fixed).
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
  int terms = 1;  ///< P R terms of step 3 (1 .. kMaxFactorTerms)
};

/// The sampling-dependent parts of the chain, shared by every texel and channel.
class ChainedFactorization {
 public:
  explicit ChainedFactorization(const ChainOptions& options);
  const ChainOptions& options() const { return o_; }
  int light_count() const { return o_.light_side * o_.light_side; }
  int view_count() const { return o_.view_side * o_.view_side; }
  int half_count() const { return o_.half_side * o_.half_side; }

  /// Factors one channel: f holds M V samples (s = view * M + light), all >= 0; p (terms x M,
  /// term k at k M), q (H) and r (terms x V) receive non-negative factors. Thread-safe.
  void factor(std::span<const double> f, std::span<double> p, std::span<double> q,
              std::span<double> r) const;

 private:
  void halfway_from_gshd(const Eigen::Ref<const Eigen::VectorXd>& f, std::span<double> q) const;
  // Steps 3's first `terms` terms.
  void divide_and_split(std::span<const double> f, std::span<double> p, std::span<double> q,
                        std::span<double> r, int terms) const;
  // Term k (0-based) of the fit of target ~ w sum P R (w empty: all 1) beside terms 0 .. k-1.
  void add_term(std::span<const double> target, std::span<const double> w, int k,
                std::span<double> p, std::span<double> r) const;
  // `refine` alternations on the first `terms` terms.
  void refine(std::span<const double> f, std::span<double> p, std::span<double> q,
              std::span<double> r, int terms) const;
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

/// Sweeps of the weighted non-negative K-term fit target_s ~ w_s sum_k p_k[j] r_k[e] (s = e M +
/// j, M = p.size() / K, V = r.size() / K), each P_k then each R_k set to its exact non-negative
/// minimiser with the rest fixed (left as it is where no sample weighs on it); w empty: all 1.
void fit_terms(std::span<const double> target, std::span<const double> w, int terms,
               std::span<double> p, std::span<double> r, int sweeps);

/// Rank-1 approximation u v^T of a rows x cols column-major non-negative matrix by power
/// iteration from the column means (the Perron vectors, so u, v >= 0); u and v share the
/// singular value as sqrt(sigma) each.
void rank_one(std::span<const double> a, int rows, int cols, std::span<double> u,
              std::span<double> v);

}  // namespace prt::cmf
