#pragma once
// Deterministic k-means (Lloyd iterations) over dense or CSR rows with dense centroids. The
// distance ||x - c||^2 is evaluated as ||x||^2 - 2 x.c + ||c||^2 so that a sparse row costs its
// non-zeros, not the dimension. Randomness comes only from the explicit seed, and the result
// does not depend on the number of threads, so a backend compressing twice with one seed gets
// identical codebooks.
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "prtlab/numeric/row_set.h"

namespace prt {

enum class KMeansInit {
  /// Linde-Buzo-Gray, as Sloan 2003 initialises CPCA: one cluster, then split centroids by a
  /// small random perturbation and refine with Lloyd iterations until there are k.
  kLbgSplitting,
  /// k-means++: each new seed is a point drawn with probability proportional to w D^2.
  kPlusPlus,
};

struct KMeansOptions {
  int clusters = 1;
  KMeansInit init = KMeansInit::kLbgSplitting;
  std::uint64_t seed = 0;
  /// Lloyd iterations after the last centroid exists; the run also stops as soon as no point
  /// changes cluster, or when the relative SSE decrease falls below `tolerance`.
  int max_iterations = 100;
  double tolerance = 0.0;
  /// Lloyd iterations after each intermediate LBG split (the final stage uses max_iterations).
  int split_iterations = 10;
  /// LBG perturbation, relative to the RMS radius of the cluster being split.
  double split_perturbation = 1e-2;
  /// Optional non-negative weight per point (empty: all 1). Centroids are weighted means and the
  /// error is the weighted sum of squared distances.
  std::span<const double> weights;
};

struct KMeansResult {
  std::vector<std::uint32_t> assignments;  ///< cluster of each point
  Eigen::MatrixXd centroids;               ///< clusters x dims, one centroid per row
  std::vector<std::size_t> counts;         ///< points per cluster
  double squared_error = 0.0;              ///< sum of w ||x - c(x)||^2 at the final assignment
  int iterations = 0;                      ///< Lloyd iterations, all LBG stages included
  /// The squared error after each Lloyd assignment of the final stage, in order.
  std::vector<double> squared_error_history;
};

/// Clusters the rows of `points`. Throws ParameterError when clusters < 1 or exceeds the number
/// of points, or when the weights are malformed (wrong length, negative, not finite, all zero).
KMeansResult kmeans(const RowSet& points, const KMeansOptions& options);

/// Lloyd iterations from given centroids (clusters x dims); options.init and options.clusters
/// are ignored. For refinement stages, e.g. CPCA's reclassification.
KMeansResult kmeans_from(const RowSet& points, const Eigen::MatrixXd& initial_centroids,
                         const KMeansOptions& options);

struct NearestCentroids {
  std::vector<std::uint32_t> assignments;
  std::vector<double> squared_distances;  ///< to the nearest centroid, clamped at 0
};

/// The nearest centroid of each point (ties go to the lower index).
NearestCentroids nearest_centroids(const RowSet& points, const Eigen::MatrixXd& centroids);

}  // namespace prt
