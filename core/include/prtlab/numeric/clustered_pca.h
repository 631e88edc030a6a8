#pragma once
// Clustered principal component analysis (CPCA, Sloan et al. 2003, sections 4.1-4.3) over the
// rows of a RowSet, dense or CSR: the points are partitioned into clusters, each approximated by
// an affine subspace, x ~ mean_c + sum_i w_i u_ci.
//
//   kStatic     LBG vector quantisation (k-means with splitting), then a PCA per cluster.
//   kIterative  classify each point to the cluster of least approximation error, recompute every
//               cluster's PCA after each classification, adding components one at a time from 0
//               to n' with `iterations_per_component` such passes for each count.
//   kAdaptive   the iterative result, then passes of: classify (each cluster with its own count),
//               PCA, and a redistribution of the components by D_i^2 / (w m_c + n) (the squared
//               error a component removes per unit of storage: its m_c weights at relative
//               cost w = adaptive_weight_cost and its own n values, the paper's storage model
//               of section 4.1) under the budget sum_c (w m_c + n) k_c <= sum_c (w m_c + n) n',
//               what the iterative result stores (rule kStorage), or the paper's own rule of
//               section 4.3 (kSloan): ranked by D_i^2 / m_c and granted in that order until
//               sum_c m_c k_c, the per-point weights, would exceed m n' (adaptive_allocation()).
//
// What keeps it fast on T's rows (6,144 columns, ~50 non-zeros): no n x n covariance is ever
// formed (truncated_pca.h works on the implicit centred operator, or C C^T for small clusters);
// a classification pass is one sparse x dense product of the rows with every cluster's mean and
// components stacked (row_products.h), fused with the error evaluation so that nothing of size
// rows x (clusters (n'+1)) is stored; the PCA after a reclassification starts from the
// cluster's previous components, which Rayleigh-Ritz then can only improve on.
//
// Error bookkeeping: a pass's error is the sum over points of the classification error; the
// result's squared_error is recomputed in double from the final model and weights.
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "prtlab/numeric/row_set.h"

namespace prt {

enum class CpcaMethod { kStatic, kIterative, kAdaptive };

/// How the adaptive method redistributes the components (adaptive_allocation()).
enum class CpcaAdaptiveRule {
  /// Rank by D_i^2 / (w m_c + n), the error removed per stored value (its m_c weights at
  /// relative cost w and its own n values); grant in that order, skipping a component that does
  /// not fit, while sum_c (w m_c + n) k_c stays within sum_c (w m_c + n) n'.
  kStorage,
  /// Sloan et al. 2003, section 4.3: rank by D_i^2 / m_c and add components in that order until
  /// sum_c m_c k_c (the per-point weights) reaches its budget m n'; the first component that
  /// would exceed it ends the allocation.
  kSloan,
};

struct CpcaPass {
  std::string stage;   ///< "vq", "iterative", "adaptive", "final"
  int components = 0;  ///< the (mean) components per cluster during the pass
  int iteration = 0;   ///< within the stage
  double squared_error = 0;
  std::size_t reassigned = 0;  ///< points that changed cluster in this pass's classification
};

struct ClusteredPcaOptions {
  int clusters = 1;    ///< m_c
  int components = 0;  ///< n': per cluster (static, iterative) or on average (adaptive)
  CpcaMethod method = CpcaMethod::kIterative;
  /// Lloyd iterations of the VQ stage (the last LBG stage; the splitting stages use 10 each).
  int vq_iterations = 20;
  /// Classification + PCA passes for each number of components (iterative, adaptive).
  int iterations_per_component = 10;
  /// Classification + PCA + redistribution passes after the iterative stage (adaptive).
  int adaptive_iterations = 5;
  /// Storage of one weight relative to one value of a stored component (adaptive): 1 when both
  /// are floats, 0.25 for s8 weights beside f32 components. The budget is in those units.
  double adaptive_weight_cost = 1.0;
  /// Most components one cluster may get (adaptive); 0: 4 n' (at least 1), capped by cols.
  int adaptive_max_components = 0;
  CpcaAdaptiveRule adaptive_rule = CpcaAdaptiveRule::kStorage;
  /// Run every PCA update to pca_tolerance (the paper's "PCA of the cluster's current point
  /// members" after each classification), not pca_iterations_per_pass warm-started subspace
  /// iterations: the adaptive ranking then reads converged D_i^2.
  bool converge_every_update = false;
  std::uint64_t seed = 0;
  /// Residual tolerance of each cluster's final PCA (truncated_pca.h; relative to its top
  /// eigenvalue).
  double pca_tolerance = 1e-6;
  /// Subspace iterations of a cluster's PCA update between two classifications. The update
  /// starts from the cluster's previous components, so successive passes continue one subspace
  /// iteration rather than restarting it, and Rayleigh-Ritz over a span holding the previous
  /// components never captures less than they did: the error still cannot grow. The last
  /// update runs to pca_tolerance.
  int pca_iterations_per_pass = 1;
  /// Extra block vectors of those passes' subspace iterations (truncated_pca.h).
  int pca_oversampling = 4;
  /// Called after every pass (progress, logging); may be empty.
  std::function<void(const CpcaPass&)> on_pass;
};

struct CpcaCluster {
  Eigen::VectorXd mean;         ///< n
  Eigen::MatrixXd components;   ///< n x k_c, orthonormal columns, decreasing eigenvalue
  Eigen::VectorXd eigenvalues;  ///< D_i^2 of the cluster's centred scatter, k_c of them
  std::size_t count = 0;        ///< m_c, points in the cluster
  int k() const { return static_cast<int>(components.cols()); }
};

/// Wall-clock seconds per phase and the classification product's work.
struct CpcaPhaseTimes {
  double vq = 0;        ///< the LBG / k-means stage
  double classify = 0;  ///< classification passes (product and error evaluation)
  double pca = 0;       ///< per-cluster PCA updates
  double weights = 0;   ///< the final projection of every point
  int classify_passes = 0;
  int pca_updates = 0;  ///< PCA updates of all clusters (one per pass)
  /// Floating-point operations of the classification products: 2 nnz K per pass, K the
  /// number of stacked means and components.
  double classify_flops = 0;
};

struct ClusteredPca {
  std::vector<std::uint32_t> assignments;  ///< cluster of each point
  std::vector<CpcaCluster> clusters;
  /// The points' weights w_i = (x - mean_c) . u_ci, point after point: point p's k_c(p) weights
  /// start at weight_offsets[p] (size points + 1).
  std::vector<double> weights;
  std::vector<std::uint64_t> weight_offsets;
  double squared_error = 0;       ///< sum_p ||x_p - x~_p||^2, in double
  double total_squared_norm = 0;  ///< sum_p ||x_p||^2 (the relative error's denominator)
  std::vector<CpcaPass> history;  ///< every pass in order
  CpcaPhaseTimes times;
  /// Stored weights: sum_c m_c k_c (m n' for static and iterative; adaptive keeps
  /// sum_c (m_c + n) k_c, weights and vectors together, within that of the iterative result).
  std::uint64_t weight_count() const { return weights.size(); }
};

/// The adaptive method's redistribution: the component count of every cluster under `rule`,
/// from each cluster's eigenvalues (D_i^2, decreasing; the candidates) and point count m_c, for
/// `components` (n') per cluster on average, weights of relative cost `weight_cost` and
/// components of `dim` values (both used by kStorage only). Clusters without points get 0.
std::vector<int> adaptive_allocation(std::span<const CpcaCluster> clusters, int components,
                                     CpcaAdaptiveRule rule, double weight_cost, std::size_t dim);

/// Throws ParameterError when clusters is not in 1..points, components is negative or above the
/// dimension, or an iteration count is negative.
ClusteredPca clustered_pca(const RowSet& points, const ClusteredPcaOptions& options);

/// An affine codebook as a renderer stores it: per cluster c the representatives
/// reps.row(first[c]) (the mean) and reps.row(first[c] + 1 + i) (component i), i < k_c =
/// first[c + 1] - first[c] - 1; point p is reconstructed as
///     x~_p = rep_0 + sum_i weights[weight_offsets[p] + i] rep_{1+i}   (reps of its cluster).
/// Returns sum_p ||x_p - x~_p||^2 in double, for representatives and weights as stored
/// (rounded to float, quantised): components need not be orthonormal.
double affine_codebook_squared_error(const RowSet& points,
                                     std::span<const std::uint32_t> assignments,
                                     const RowMajorMatrixXd& reps,
                                     std::span<const std::uint32_t> first,
                                     std::span<const double> weights,
                                     std::span<const std::uint64_t> weight_offsets);

}  // namespace prt
