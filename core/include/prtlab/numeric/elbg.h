#pragma once
// Enhanced LBG vector quantisation (Patane and Russo 2001), the initialisation the clustered
// tensor approximation of Tsai and Shih 2006 uses. Lloyd iterations stop in a local minimum where
// some codewords serve little distortion and others a lot; ELBG's "shift of codeword attempt"
// moves a low-utility codeword (utility = its cell's distortion over the mean cell distortion)
// into the cell of a high-utility one, merges the abandoned cell into its nearest codeword, and
// keeps the move only when the distortion of the three cells involved decreases. Between rounds a
// global Lloyd pass reassigns every point. The distortion never increases from round to round.
//
// Two choices differ from the 2001 paper, for high-dimensional points (a vertex's unfolded
// transfer, thousands of dimensions): the two codewords of a split cell start on its principal
// axis (centroid -/+ the RMS spread along it) instead of the diagonal of its bounding box, which
// in thousands of dimensions points nowhere in particular; and the high-utility cell a low one
// moves to is taken in decreasing utility instead of by roulette, so that the result depends on
// the seed of the initial k-means only.
#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

namespace prt {

struct ElbgOptions {
  int clusters = 1;
  std::uint64_t seed = 0;       ///< of the k-means++ seeding
  int rounds = 10;              ///< ELBG rounds (shift attempts, then one Lloyd pass) at most
  int initial_iterations = 10;  ///< Lloyd iterations of the initial k-means
  int local_iterations = 4;     ///< two-codeword Lloyd iterations inside a split cell
  /// Stop when a round lowers the distortion by less than this fraction.
  double tolerance = 1e-4;
};

struct ElbgResult {
  std::vector<std::uint32_t> assignments;  ///< cluster of each point
  Eigen::MatrixXd centroids;               ///< clusters x dims
  std::vector<std::size_t> counts;
  double squared_error = 0;          ///< sum of ||x - c(x)||^2 at the final assignment
  double initial_squared_error = 0;  ///< of the initial k-means
  int rounds = 0;
  int shifts_tried = 0;
  int shifts_accepted = 0;
  /// The distortion after each round's Lloyd pass.
  std::vector<double> squared_error_history;
};

/// Quantises `points` (rows x cols, row-major, dense). Throws ParameterError when the shape is
/// inconsistent, clusters < 1 or clusters > rows, or a value is not finite.
ElbgResult elbg(std::span<const float> points, std::size_t rows, std::size_t cols,
                const ElbgOptions& options);
/// The same from given centroids (clusters x cols), skipping the initial k-means.
ElbgResult elbg_from(std::span<const float> points, std::size_t rows, std::size_t cols,
                     const Eigen::MatrixXd& initial_centroids, const ElbgOptions& options);

}  // namespace prt
