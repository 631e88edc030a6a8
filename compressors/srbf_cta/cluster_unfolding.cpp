#include "srbf_cta/cluster_unfolding.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <random>

#include "prtlab/base/error.h"
#include "prtlab/numeric/symmetric_eigen.h"

namespace prt::srbf_cta {
namespace {

using MatF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using MapF = Eigen::Map<const MatF>;

/// Fixed blocks of [0, n), each handled by one call of f(begin, end): which thread runs a block
/// never changes what it computes.
template <class F>
void for_blocks(Eigen::Index n, Eigen::Index block, F&& f) {
  const Eigen::Index blocks = (n + block - 1) / block;
  tbb::parallel_for(
      tbb::blocked_range<Eigen::Index>(0, blocks, 1),
      [&](const tbb::blocked_range<Eigen::Index>& r) {
        for (Eigen::Index b = r.begin(); b != r.end(); ++b)
          f(b * block, std::min(n, (b + 1) * block));
      },
      tbb::simple_partitioner());
}

constexpr Eigen::Index kMemberBlock = 32;    // rows of Z gathered for one product
constexpr Eigen::Index kColumnBlock = 2048;  // Z's columns one task sums over the members

/// sum_k a(k, :) Z_{members[k]} as (R1 I2) x k, in Scalar: column blocks in parallel, member
/// blocks in order within each.
template <class Scalar>
Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic> transpose_product(
    const float* z, Eigen::Index zsize, std::span<const std::uint32_t> members,
    const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>& a) {
  using Mat = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
  using RowMat = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const auto m = static_cast<Eigen::Index>(members.size());
  Mat g = Mat::Zero(zsize, a.cols());
  for_blocks(zsize, kColumnBlock, [&](Eigen::Index c0, Eigen::Index c1) {
    const Eigen::Index len = c1 - c0;
    RowMat chunk(kMemberBlock, len);
    for (Eigen::Index k0 = 0; k0 < m; k0 += kMemberBlock) {
      const Eigen::Index n = std::min(kMemberBlock, m - k0);
      for (Eigen::Index i = 0; i < n; ++i)
        chunk.row(i) = Eigen::Map<const Eigen::RowVectorXf>(
                           z + static_cast<std::size_t>(members[k0 + i]) * zsize + c0, len)
                           .template cast<Scalar>();
      g.middleRows(c0, len).noalias() += chunk.topRows(n).transpose() * a.middleRows(k0, n);
    }
  });
  return g;
}

/// Z_c b (m x k) for b (R1 I2) x k, in Scalar, over fixed member blocks.
template <class Scalar>
void members_product(const float* z, Eigen::Index zsize, std::span<const std::uint32_t> members,
                     const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>& b,
                     Eigen::MatrixXd& out) {
  using RowMat = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const auto m = static_cast<Eigen::Index>(members.size());
  out.resize(m, b.cols());
  for_blocks(m, kMemberBlock, [&](Eigen::Index k0, Eigen::Index k1) {
    RowMat chunk(k1 - k0, zsize);
    for (Eigen::Index i = k0; i < k1; ++i)
      chunk.row(i - k0) = Eigen::Map<const Eigen::RowVectorXf>(
                              z + static_cast<std::size_t>(members[i]) * zsize, zsize)
                              .template cast<Scalar>();
    out.middleRows(k0, k1 - k0) = (chunk * b).template cast<double>();
  });
}

Eigen::MatrixXd orthonormal_basis(const Eigen::MatrixXd& a) {
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(a);
  return qr.householderQ() * Eigen::MatrixXd::Identity(a.rows(), a.cols());
}

/// Orthonormalises the columns of x in place by Cholesky QR, twice (CholeskyQR2: orthonormal to
/// rounding when x is well conditioned), at the cost of two small Gram matrices instead of a
/// Householder QR of a tall matrix. False, x unchanged, when x is too close to rank deficient.
bool cholesky_orthonormalise(Eigen::MatrixXd& x) {
  Eigen::MatrixXd q = x;
  for (int pass = 0; pass < 2; ++pass) {
    const Eigen::MatrixXd g = q.transpose() * q;
    const Eigen::LLT<Eigen::MatrixXd> llt(g);
    if (llt.info() != Eigen::Success) return false;
    const Eigen::VectorXd d = llt.matrixLLT().diagonal();
    if (d.size() == 0 || !(d.minCoeff() > 1e-6 * d.maxCoeff())) return false;
    q = llt.matrixL().solve(q.transpose()).transpose();
  }
  x = std::move(q);
  return true;
}

}  // namespace

ClusterUnfolding::ClusterUnfolding(const float* z, Eigen::Index r1, Eigen::Index i2,
                                   std::span<const std::uint32_t> members,
                                   const Eigen::MatrixXd& light, Eigen::Index vectors,
                                   int expected_products, Representation representation)
    : z_(z),
      r1_(r1),
      i2_(i2),
      r2_(light.cols()),
      m_(static_cast<Eigen::Index>(members.size())),
      members_(members),
      light_(light) {
  // Multiply-adds: forming Y then products in double, against products through Z in float
  // (about twice as fast per multiply-add). Y in double is kept under 2 GiB.
  const double rows = static_cast<double>(m_), w = static_cast<double>(r1_ * r2_),
               zs = static_cast<double>(r1_ * i2_), nv = static_cast<double>(vectors),
               np = static_cast<double>(expected_products);
  const double formed_cost = rows * zs * static_cast<double>(r2_) + np * rows * w * nv;
  const double implicit_cost = 0.5 * np * (rows * zs * nv + nv * zs * static_cast<double>(r2_));
  formed_ = representation == Representation::kFormed ||
            (representation == Representation::kAuto && formed_cost <= implicit_cost &&
             rows * w * 8.0 <= 2.0 * (1u << 30));
  if (!formed_) return;
  y_.resize(m_, r1_ * r2_);
  const Eigen::MatrixXf lf = light.cast<float>();
  const Eigen::Index zsize = r1_ * i2_;
  tbb::parallel_for(Eigen::Index{0}, m_, [&](Eigen::Index k) {
    const MatF p = MapF(z_ + static_cast<std::size_t>(members_[k]) * zsize, r1_, i2_) * lf;
    y_.row(k) = Eigen::Map<const Eigen::RowVectorXf>(p.data(), r1_ * r2_).cast<double>();
  });
}

void ClusterUnfolding::apply(const Eigen::MatrixXd& v, Eigen::MatrixXd& out, bool exact) const {
  if (formed_) {
    out.resize(m_, v.cols());
    for_blocks(m_, 64, [&](Eigen::Index k0, Eigen::Index k1) {
      out.middleRows(k0, k1 - k0).noalias() = y_.middleRows(k0, k1 - k0) * v;
    });
    return;
  }
  // b_j = vec(refold(v_j) U_c^T): the vector in the SRBF coordinates of Z.
  const Eigen::Index zsize = r1_ * i2_;
  Eigen::MatrixXd b(zsize, v.cols());
  tbb::parallel_for(Eigen::Index{0}, v.cols(), [&](Eigen::Index j) {
    const Eigen::Map<const RowMajorMatrixXd> p(v.col(j).data(), r1_, r2_);
    const RowMajorMatrixXd bj = p * light_.transpose();
    b.col(j) = Eigen::Map<const Eigen::VectorXd>(bj.data(), zsize);
  });
  if (exact)
    members_product<double>(z_, zsize, members_, b, out);
  else
    members_product<float>(z_, zsize, members_, Eigen::MatrixXf(b.cast<float>()), out);
}

void ClusterUnfolding::apply_transpose(const Eigen::MatrixXd& a, Eigen::MatrixXd& out,
                                       bool exact) const {
  out.resize(r1_ * r2_, a.cols());
  if (formed_) {
    for_blocks(r1_ * r2_, 256, [&](Eigen::Index c0, Eigen::Index c1) {
      out.middleRows(c0, c1 - c0).noalias() = y_.middleCols(c0, c1 - c0).transpose() * a;
    });
    return;
  }
  const Eigen::Index zsize = r1_ * i2_;
  const Eigen::MatrixXd g =
      exact ? transpose_product<double>(z_, zsize, members_, a)
            : Eigen::MatrixXd(
                  transpose_product<float>(z_, zsize, members_, Eigen::MatrixXf(a.cast<float>()))
                      .cast<double>());
  tbb::parallel_for(Eigen::Index{0}, a.cols(), [&](Eigen::Index j) {
    const Eigen::Map<const RowMajorMatrixXd> gj(g.col(j).data(), r1_, i2_);
    const RowMajorMatrixXd p = gj * light_;
    out.col(j) = Eigen::Map<const Eigen::VectorXd>(p.data(), r1_ * r2_);
  });
}

void ClusterUnfolding::transpose(Eigen::MatrixXd& out) const {
  if (formed_)
    out = y_.transpose();
  else
    apply_transpose(Eigen::MatrixXd::Identity(m_, m_), out, true);
}

Eigen::MatrixXd members_transpose_product(const float* z, Eigen::Index zsize,
                                          std::span<const std::uint32_t> members,
                                          const Eigen::MatrixXd& a) {
  return transpose_product<double>(z, zsize, members, a);
}

VertexMode top_vertex_mode(const ClusterUnfolding& y, const VertexModeOptions& o,
                           const Eigen::MatrixXd* start_right, const Eigen::MatrixXd* start_left) {
  const Eigen::Index m = y.rows(), w = y.cols();
  const Eigen::Index r = std::min({o.rank, m, w});
  const Eigen::Index k = std::min({r + o.oversampling, m, w});
  VertexMode out;
  if (r <= 0) {
    out.v.resize(w, 0);
    out.weights.resize(m, 0);
    return out;
  }
  // The exact path costs the m x m Gram matrix and its eigen-decomposition; an iteration of the
  // subspace method two products with k vectors (estimated: 3 iterations from a warm start,
  // 6 from a random one).
  const double dm = static_cast<double>(m), dw = static_cast<double>(w),
               dk = static_cast<double>(k), zs = static_cast<double>(y.zsize()),
               r2 = static_cast<double>(y.light_rank());
  const bool warm = start_right != nullptr || start_left != nullptr;
  const double gram_cost =
      (y.formed() ? 0.5 * dm * dm * dw : 2 * dm * dm * zs + dm * zs * r2 + 0.5 * dm * dm * dw) +
      4 * dm * dm * dm;
  const double iteration_cost =
      y.formed() ? 4 * dm * dw * dk : 0.5 * (4 * dm * zs * dk + 4 * dk * zs * r2);
  if (w <= 2 * k) {
    // Few columns: Y itself (m x w, exact) and the w x w Gram matrix.
    Eigen::MatrixXd full;
    y.apply(Eigen::MatrixXd::Identity(w, w), full, true);
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(full.transpose() * full);
    if (eig.info() != Eigen::Success)
      throw Error("srbf_cta: the eigen-decomposition of a vertex Gram matrix did not converge");
    out.v = eig.eigenvectors().rightCols(r).rowwise().reverse();
    out.sigma = eig.eigenvalues().tail(r).reverse().cwiseMax(0.0).cwiseSqrt();
    out.weights = full * out.v;
    return out;
  }
  if (m <= 2 * k || gram_cost <= (warm ? 3.0 : 6.0) * iteration_cost) {
    // Exact: the m x m Gram matrix of Y from Y^T (w x m), its lower triangle (all the solver
    // reads), then v = Y^T u / sigma orthonormalised to rounding (callers rely on V^T V = I).
    Eigen::MatrixXd yt;
    y.transpose(yt);
    Eigen::MatrixXd g = Eigen::MatrixXd::Zero(m, m);
    g.selfadjointView<Eigen::Lower>().rankUpdate(yt.transpose());
    const SymmetricEigen eig = top_symmetric_eigen(g, r);
    const Eigen::MatrixXd& u = eig.vectors;
    out.sigma = eig.values.cwiseMax(0.0).cwiseSqrt();
    Eigen::MatrixXd v = yt * u;
    Eigen::Index kept = 0;
    while (kept < r && out.sigma[kept] > 0) ++kept;
    for (Eigen::Index j = 0; j < kept; ++j) v.col(j) /= out.sigma[j];
    // Directions without a singular value are completed orthonormally by the QR.
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(v);
    Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(w, r);
    for (Eigen::Index j = 0; j < r; ++j)
      if (qr.matrixQR()(j, j) < 0) q.col(j) *= -1.0;
    out.v = std::move(q);
    out.weights = yt.transpose() * out.v;
    return out;
  }

  // The start block: the previous basis, then Y^T of the previous left vectors, then random.
  Eigen::MatrixXd v0(w, k);
  Eigen::Index filled = 0;
  if (start_right != nullptr && start_right->rows() == w) {
    const Eigen::Index n = std::min(k, start_right->cols());
    v0.leftCols(n) = start_right->leftCols(n);
    filled = n;
  }
  if (start_left != nullptr && start_left->rows() == m && filled < k) {
    const Eigen::Index n = std::min(k - filled, start_left->cols());
    Eigen::MatrixXd img;
    y.apply_transpose(start_left->leftCols(n), img);
    v0.middleCols(filled, n) = img;
    filled += n;
  }
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> normal;
  for (Eigen::Index j = filled; j < k; ++j)
    for (Eigen::Index i = 0; i < w; ++i) v0(i, j) = normal(rng);
  Eigen::MatrixXd v = v0;
  if (!cholesky_orthonormalise(v)) v = orthonormal_basis(v0);
  Eigen::MatrixXd a;
  y.apply(v, a);
  Eigen::VectorXd lambda;
  double previous = -1;
  for (int it = 0; it < o.max_iterations; ++it) {
    Eigen::MatrixXd b;
    y.apply_transpose(a, b);
    // The new directions: the part of B orthogonal to V, completed orthonormally (and still
    // orthogonal to V) where Y's rank leaves B short of k independent columns.
    for (int pass = 0; pass < 2; ++pass) b -= v * (v.transpose() * b);
    Eigen::MatrixXd qb = std::move(b);
    if (!cholesky_orthonormalise(qb)) {
      Eigen::MatrixXd vb(w, 2 * k);
      vb << v, qb;
      qb = orthonormal_basis(vb).rightCols(k);
    }
    Eigen::MatrixXd c;
    y.apply(qb, c);
    Eigen::MatrixXd yw(m, 2 * k);
    yw << a, c;
    const Eigen::MatrixXd gram = yw.transpose() * yw;
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(gram);
    if (eig.info() != Eigen::Success)
      throw Error("srbf_cta: the Rayleigh-Ritz step of a vertex subspace did not converge");
    const Eigen::MatrixXd g = eig.eigenvectors().rightCols(k).rowwise().reverse();
    lambda = eig.eigenvalues().tail(k).reverse().cwiseMax(0.0);
    Eigen::MatrixXd vw(w, 2 * k);
    vw << v, qb;
    v = vw * g;
    a = yw * g;
    out.iterations = it + 1;
    const double captured = lambda.head(r).sum();
    if (previous >= 0 && captured - previous <= o.tolerance * captured) break;
    previous = captured;
  }
  // V = W G with W and G orthonormal; a last orthonormalisation removes the products'
  // rounding (Cholesky QR keeps each column's direction: R's diagonal is positive).
  out.v = v.leftCols(r);
  if (!cholesky_orthonormalise(out.v)) out.v = orthonormal_basis(Eigen::MatrixXd(v.leftCols(r)));
  out.sigma = lambda.head(r).cwiseSqrt();
  y.apply(out.v, out.weights, true);
  return out;
}

}  // namespace prt::srbf_cta
