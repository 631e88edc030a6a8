#pragma once
// Clustered tensor approximation (Tsai and Shih 2006, section 5.2): the per-vertex matrices
// X_x (I1 x I2: view x light) form a third-order tensor I1 x I2 x vertices. Vertices are split
// into clusters; every cluster c has a light basis U_c (I2 x R2) and a dual vertex basis V_c
// (R3 x R1 R2, orthonormal rows), and all clusters share one view basis U (I1 x R1):
//
//   W_x      = V_c vec(U^T X_x U_c)                       (eq. 17, the projected weights)
//   X~_x     = U refold(V_c^T W_x) U_c^T                  (eq. 18)
//   error(x, c) = ||X_x||^2 - ||W_x||^2                    (all bases orthonormal)
//
// Phases: initialisation (U from the mode-1 unfolding of the whole tensor, Z_x = U^T X_x, ELBG on
// the unfolded Z_x); clustering (per cluster the N-mode SVD of its sub-tensor in modes 2 and 3,
// the dual basis of eq. 16, every vertex reclassified by eq. 18's error, until no vertex moves
// or an iteration cap); approximation (U re-extracted from all clusters' projected sub-tensors,
// then every cluster's bases again, until the error converges).
//
// The N-mode SVD is HOOI warm-started from the cluster's previous light basis, with the vertex
// basis computed first: each step maximises the core's norm given the other basis, so the total
// error never increases, neither at a reclassification (a vertex moves only to a strictly lower
// error, evaluated in double) nor at a refit (README, "Why the error never increases").
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace prt::srbf_cta {

using RowMajorMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// vertices x view x light floats: vertex x's I1 x I2 matrix, row-major, at x * I1 * I2.
struct TensorView {
  std::span<const float> values;
  std::size_t vertices = 0, view = 0, light = 0;
  const float* vertex(std::size_t x) const { return values.data() + x * view * light; }
};

struct CtaPass {
  std::string phase;  ///< "clustering" or "approximation"
  int iteration = 0;
  double squared_error = 0;  ///< total, after the pass
  std::size_t moved = 0;     ///< vertices that changed cluster (clustering)
};

struct CtaModel;

/// The state a clustering run continues from: the model after its initialisation
/// (model.clustering_iterations == 0) or after a clustering iteration, and every cluster's
/// vertex basis U_v (members x r, in member order). The Z_x are recomputed from the view basis.
struct CtaCheckpoint;

struct CtaOptions {
  int clusters = 16;
  int rank_view = 0;  ///< R1; 0: I1 (no view truncation)
  int rank_light = 48;
  int rank_vertex = 24;
  int clustering_iterations = 20;
  /// The clustering phase also stops when an iteration (reclassification and refits) lowers the
  /// total error by at most this fraction of it (0: only when no vertex moves).
  double clustering_tolerance = 1e-3;
  int approximation_iterations = 5;
  /// HOOI sweeps (light basis, then vertex basis) per cluster refit.
  int hooi_sweeps = 1;
  /// The approximation phase stops when a pass lowers the error by less than this fraction.
  double tolerance = 1e-4;
  std::uint64_t seed = 0;
  int elbg_rounds = 10;
  /// ELBG quantises the Z_x in their top elbg_dims principal directions (0: in full).
  int elbg_dims = 256;
  std::function<void(const CtaPass&)> on_pass;
  /// Called after the initialisation and after every clustering iteration that leaves more to
  /// do, with the state a resumed run needs (srbf_cta stores it in the stage cache).
  std::function<void(const CtaCheckpoint&)> on_checkpoint;
  /// A state that on_checkpoint handed out for the same tensor and options: the run continues
  /// from it and ends with the model an uninterrupted run gives, bit for bit.
  const CtaCheckpoint* resume = nullptr;
};

struct CtaCluster {
  Eigen::MatrixXd light;  ///< U_c: I2 x R2, orthonormal columns
  /// V_c: r x (R1 R2) with r <= R3 the cluster's vertex rank, orthonormal rows; element
  /// (j, a R2 + b) multiplies (U^T X U_c)(a, b).
  RowMajorMatrixXd dual;
  std::vector<std::uint32_t> members;
  double squared_error = 0;  ///< of its members
};

struct CtaTimes {
  double initialisation = 0, clustering = 0, approximation = 0;  ///< seconds
};

struct CtaModel {
  std::size_t view = 0, light = 0;  ///< I1, I2
  int rank_view = 0, rank_light = 0, rank_vertex = 0;
  Eigen::MatrixXd view_basis;  ///< U: I1 x R1, orthonormal columns
  std::vector<CtaCluster> clusters;
  std::vector<std::uint32_t> assignments;
  RowMajorMatrixXd weights;  ///< vertices x R3: W_x (0 beyond its cluster's rank)
  double total_squared_norm = 0;
  double squared_error = 0;  ///< sum over vertices of ||X_x - X~_x||^2
  /// Total error with each reclassification's bases: before it, then after it (clustering
  /// iteration i at 2i and 2i + 1).
  std::vector<double> reclassification_errors;
  std::vector<double> refit_errors;  ///< after every refit, both phases, in order
  int clustering_iterations = 0, approximation_iterations = 0;
  double elbg_squared_error = 0;  ///< of the initial quantisation of the Z_x
  CtaTimes times;
};

struct CtaCheckpoint {
  CtaModel model;
  std::vector<Eigen::MatrixXd> vertex_bases;
  bool clustering_converged = false;  ///< no vertex moved: the clustering phase is over
};

/// Throws ParameterError for an inconsistent view, no vertices, or ranks / clusters below 1.
CtaModel clustered_tensor_approximation(const TensorView& t, const CtaOptions& o);

/// X~_x (I1 x I2) of vertex x.
RowMajorMatrixXd reconstruct_vertex(const CtaModel& m, std::size_t x);

/// ||X_x - X~_x||^2 of vertex x if it were approximated in cluster c (eq. 18), in double.
double vertex_cluster_error(const TensorView& t, const CtaModel& m, std::size_t x, std::size_t c);

}  // namespace prt::srbf_cta
