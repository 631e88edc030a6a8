#pragma once
// The exact relight L* = T L (DESIGN.md "Data flow"): the reference every compressor is
// measured against, and its speed baselines.
//
// `light` is the light vector of cubemap.h (L_k = radiance_k * solidAngle_k, RGB float, size
// N); the result has one RGB value per row of T (vertex * M + j), in the pixel basis.
//
//   relight_exact         C++ CSR product, float accumulation, TBB over row blocks (or one
//                         thread), four independent accumulators per row; the u8 counts are
//                         summed against the light and the row is scaled by 1/s^2 once.
//   relight_exact_double  the same sum accumulated in double: the reference for float error.
//   EigenSparseTransfer   Eigen::SparseMatrix<float, RowMajor> times an N x 3 column-major
//                         dense matrix, written the usual way (outside baseline).
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <span>
#include <vector>

#include "prtlab/transfer/local_radiance.h"
#include "prtlab/transfer/transfer_matrix.h"
#include "prtlab/base/types.h"

namespace prt {

enum class RelightThreads { kAll, kOne };

/// out = T light; out.size() must be T.rows() and light.size() T.cols().
void relight_exact(const TransferMatrix& t, std::span<const Rgb> light, std::span<Rgb> out,
                   RelightThreads threads = RelightThreads::kAll);
/// The same, into a pixel-basis LocalRadiance (dim M, T.vertex_count() vertices).
LocalRadiance relight_exact(const TransferMatrix& t, std::span<const Rgb> light);
/// Double-accumulation reference of the same product.
std::vector<Vec3d> relight_exact_double(const TransferMatrix& t, std::span<const Rgb> light);

/// T as an Eigen sparse matrix (float values count / s^2).
class EigenSparseTransfer {
 public:
  using Sparse = Eigen::SparseMatrix<float, Eigen::RowMajor, int>;
  using Dense = Eigen::Matrix<float, Eigen::Dynamic, 3>;  ///< column-major, one column per channel

  explicit EigenSparseTransfer(const TransferMatrix& t);

  const Sparse& matrix() const { return matrix_; }
  /// light (N RGB values) as an N x 3 matrix.
  static Dense to_dense(std::span<const Rgb> light);
  /// out = T light (out resized by Eigen).
  void multiply(const Dense& light, Dense& out) const { out.noalias() = matrix_ * light; }
  /// Convenience with the same spans as relight_exact (converts in and out).
  void relight(std::span<const Rgb> light, std::span<Rgb> out) const;

 private:
  Sparse matrix_;
};

}  // namespace prt
