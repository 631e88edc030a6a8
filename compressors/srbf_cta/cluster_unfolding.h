#pragma once
// The vertex-mode unfolding of one cluster's sub-tensor, projected on the cluster's light basis:
//
//   Y (m x R1 R2),  row k = vec(Z_x U_c) for member x = members[k]   (Z_x: R1 x I2, row-major)
//
// and its top right singular vectors, which are the dual vertex basis V_c of eq. 16.
//
// Y is either formed (m R1 I2 R2 multiply-adds, then m R1 R2 per product with a vector) or
// applied through the members' Z_x without being formed (m R1 I2 per product, plus R1 I2 R2 to
// move a vector between the light basis and the SRBFs). Which is cheaper depends on the cluster:
// forming Y pays on a small light rank (the bunny at R2 = 134), applying it on a large cluster
// at a large light rank (the chair, R2 = 419 of 642, thousands of members), where Y alone would
// be gigabytes. Every product runs over fixed blocks of rows or columns, each block summed
// sequentially, so the result does not depend on the thread count.
#include <Eigen/Core>
#include <cstdint>
#include <span>

#include "srbf_cta/clustered_tensor.h"

namespace prt::srbf_cta {

class ClusterUnfolding {
 public:
  enum class Representation { kAuto, kFormed, kImplicit };

  /// `z` holds every vertex's Z_x (r1 x i2 floats, row-major) at x * r1 * i2; `light` is U_c
  /// (i2 x r2). `vectors` is how many vectors the caller will apply Y to at a time, for the cost
  /// model that picks the formed or the implicit representation.
  ClusterUnfolding(const float* z, Eigen::Index r1, Eigen::Index i2,
                   std::span<const std::uint32_t> members, const Eigen::MatrixXd& light,
                   Eigen::Index vectors, int expected_products,
                   Representation representation = Representation::kAuto);

  Eigen::Index rows() const { return m_; }
  Eigen::Index cols() const { return r1_ * r2_; }
  bool formed() const { return formed_; }
  Eigen::Index zsize() const { return r1_ * i2_; }  ///< R1 I2, the length of a member's Z_x
  Eigen::Index light_rank() const { return r2_; }

  /// out = Y v (m x k), v: (R1 R2) x k. The implicit representation multiplies in float
  /// (an iteration's products); `exact` forces double precision (the final weights).
  void apply(const Eigen::MatrixXd& v, Eigen::MatrixXd& out, bool exact = false) const;
  /// out = Y^T a ((R1 R2) x k), a: m x k; `exact` as for apply.
  void apply_transpose(const Eigen::MatrixXd& a, Eigen::MatrixXd& out, bool exact = false) const;
  /// out = Y^T ((R1 R2) x m) in double: a copy when formed, else Y^T I.
  void transpose(Eigen::MatrixXd& out) const;

 private:
  const float* z_;
  Eigen::Index r1_, i2_, r2_, m_;
  std::span<const std::uint32_t> members_;
  const Eigen::MatrixXd& light_;
  bool formed_ = false;
  RowMajorMatrixXd y_;  ///< formed: m x R1 R2
};

/// sum_k a(k, j) Z_{members[k]} for every column j of a (m x k): (R1 I2) x k, column j the
/// row-major R1 x I2 matrix flattened. In double, over fixed column blocks, members in order.
Eigen::MatrixXd members_transpose_product(const float* z, Eigen::Index zsize,
                                          std::span<const std::uint32_t> members,
                                          const Eigen::MatrixXd& a);

struct VertexMode {
  Eigen::MatrixXd v;        ///< (R1 R2) x r, orthonormal columns: the dual basis, transposed
  Eigen::VectorXd sigma;    ///< r singular values, decreasing
  Eigen::MatrixXd weights;  ///< m x r: Y v in double, W_x in rows
  int iterations = 0;       ///< subspace iterations (0: exact, from the Gram matrix)
};

struct VertexModeOptions {
  Eigen::Index rank = 1;
  int oversampling = 8;
  int max_iterations = 60;
  /// Stop when an iteration raises the captured energy (the sum of the top `rank` squared
  /// singular values) by at most this fraction of it.
  double tolerance = 1e-6;
  std::uint64_t seed = 0;
};

/// The top `rank` right singular vectors of Y. Exact from the m x m Gram matrix when that costs
/// less than a few iterations (small clusters), else by a block subspace iteration with
/// Rayleigh-Ritz over [V, Y^T Y V], which contains V: the captured energy never falls, so starting
/// from the cluster's previous basis (`start_right`, R1 R2 columns, or `start_left`, m columns
/// whose image Y^T a opens the block) can only keep or improve it, which is what HOOI's monotone
/// error needs. Random columns (from `seed`) fill the block.
VertexMode top_vertex_mode(const ClusterUnfolding& y, const VertexModeOptions& o,
                           const Eigen::MatrixXd* start_right, const Eigen::MatrixXd* start_left);

}  // namespace prt::srbf_cta
