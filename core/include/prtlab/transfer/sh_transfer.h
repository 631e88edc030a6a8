#pragma once
// Per-vertex SH transfer matrices (for the SH bi-scale backend, Sloan 2004), computed from the
// same supersampled visibility as T (docs/transfer.md).
//
// Meaning. Let the distant light be an SH expansion L(d) = sum_k l_k y_k(d) in the global
// frame (spherical_harmonics.h: z is the polar axis of the basis functions, in world
// coordinates). The incident radiance at vertex p, expressed in p's local frame F (t, b, n:
// local z = normal) and masked by visibility V_p and by the upper hemisphere, is
//     L_p(w) = V_p(F w) L(F w)   for w.z > 0,   0 for w.z <= 0.
// Its SH coefficients in the local frame are c_i = sum_k M_p[i][k] l_k with
//     M_p[i][k] = integral over the sphere of y_i(F^T d) y_k(d) V_p(d) [d.n > 0] dd.
// There is no cosine factor: M_p yields incident radiance, not irradiance; the BTF/RTT side
// carries the cosine. M_p is not symmetric.
//
// Quadrature: the sum over the unblocked supersampled sub-rays r (those strictly above the
// tangent plane that escape) of y_i(F^T d_r) y_k(d_r) dOmega_r, with dOmega_r the exact solid
// angle of the sub-pixel. Accumulated and stored in double, n^2 values per vertex, row-major:
// matrix(v)[i * n + k] with i the local and k the global index.
#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "prtlab/sphere/local_frame.h"
#include "prtlab/base/types.h"

namespace prt {

class SupersampledCubemap;

class ShTransfer {
 public:
  using MatrixMap =
      Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;

  ShTransfer() = default;
  /// Zero matrices for `vertices` points, SH order 1..10 (n = order^2).
  ShTransfer(int order, std::size_t vertices);

  int order() const { return order_; }
  int dim() const { return order_ * order_; }  ///< n
  std::size_t vertex_count() const { return vertices_; }
  /// All matrices, vertex after vertex, each n x n row-major.
  std::span<const double> data() const { return data_; }
  std::span<double> mutable_data() { return data_; }
  std::span<const double> matrix(std::size_t v) const;
  std::span<double> mutable_matrix(std::size_t v);
  MatrixMap map(std::size_t v) const;

  /// local[i] = sum_k M_v[i][k] light[k], per RGB channel (both of size n).
  void apply(std::size_t v, std::span<const Vec3d> light, std::span<Vec3d> local) const;

  friend bool operator==(const ShTransfer&, const ShTransfer&) = default;

 private:
  int order_ = 0;
  std::size_t vertices_ = 0;
  std::vector<double> data_;
};

/// Quadrature of one point's SH transfer from its unblocked sub-rays (the per-vertex step of
/// compute_transfer, exposed for tests).
///
/// It uses M_p = R_p V_p, an exact identity for the quadrature sum: y(F^T d) = R_p y(d) for
/// every direction d, with R_p the SH rotation matrix of F^T (block diagonal by band), so
///     sum_r y(F^T d_r) y(d_r)^T w_r = R_p sum_r y(d_r) y(d_r)^T w_r = R_p V_p.
/// V_p is symmetric (a rank-k update over the unblocked sub-rays, from a table of
/// y(d_r) sqrt(dOmega_r)), and R_p is solved once per point from the SH of a fixed set of
/// 2 n + 16 directions (least squares, exact since rotations keep every band). This halves
/// the multiply-adds of the direct sum and needs no SH evaluation per ray.
class ShTransferIntegrator {
 public:
  ShTransferIntegrator(const SupersampledCubemap& dirs, int order);

  int order() const { return order_; }
  /// Scratch buffers, one per thread.
  struct Scratch {
    std::vector<double> panel, gram, rotation, local;
  };
  /// out (n x n row-major) = sum over r in `unblocked` of y(F^T d_r) y(d_r)^T dOmega_r.
  void integrate(const LocalFrame& frame, std::span<const std::uint32_t> unblocked,
                 std::span<double> out, Scratch& scratch) const;
  /// R with y(F^T d) = R y(d) (n x n row-major), for tests.
  void rotation(const LocalFrame& frame, std::span<double> out, Scratch& scratch) const;

 private:
  const SupersampledCubemap* dirs_;
  int order_;
  std::vector<double> table_;   ///< subray_count x n: y_k(d_r) sqrt(dOmega_r)
  std::vector<Vec3d> samples_;  ///< P fixed directions for solving R
  std::vector<double> pinv_;    ///< n x P row-major: pseudo-inverse of [y(samples)] (P x n)
};

}  // namespace prt
