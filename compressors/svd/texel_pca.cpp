#include "svd/texel_pca.h"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "prtlab/base/error.h"
#include "prtlab/numeric/symmetric_eigen.h"

namespace prt::svd {

SvdState texel_pca(const Btf& btf, int rank) {
  const int n = btf.texel_count();
  const Eigen::Index d = static_cast<Eigen::Index>(btf.view_count()) * btf.light_count() * 3;
  const Eigen::Index limit = std::min<Eigen::Index>(n, d);
  if (n > kMaxPcaTexels)
    throw ParameterError(fmt::format(
        "material svd: mode texel_pca takes at most {} texels (its U^2 x U^2 Gram matrix); BTF "
        "'{}' has {}",
        kMaxPcaTexels, btf.material(), n));
  if (rank < 1 || rank > limit)
    throw ParameterError(fmt::format(
        "material svd: rank {} is outside [1, min(U^2, 3 M V)] = [1, {}] for BTF '{}' (mode "
        "texel_pca)",
        rank, limit, btf.material()));
  // Rows are texels: the BTF's layout holds each texel's 3 M V values contiguously.
  const Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> raw(
      btf.data().data(), n, d);
  Eigen::MatrixXd x = raw.cast<double>();
  const double total = x.squaredNorm();
  const Eigen::RowVectorXd mean = x.colwise().mean();
  x.rowwise() -= mean;

  Eigen::MatrixXd gram(n, n);
  gram.setZero();
  gram.selfadjointView<Eigen::Lower>().rankUpdate(x);
  // numeric/symmetric_eigen.h (LAPACK where the build has it). A small rank asks for its top
  // eigenpairs only and discards the trace less what they keep (exact but for a few ulps of the
  // trace); a large one, which may discard next to nothing, asks for the whole spectrum and sums
  // the small eigenvalues themselves.
  const bool whole = 8 * static_cast<Eigen::Index>(rank) > n;
  const SymmetricEigen eig = top_symmetric_eigen(gram, whole ? n : rank);
  double discarded = 0;
  if (whole) {
    for (Eigen::Index i = rank; i < n; ++i) discarded += std::max(eig.values[i], 0.0);
  } else {
    discarded = std::max(0.0, gram.diagonal().sum() - eig.values.cwiseMax(0.0).sum());
  }

  // Principal directions from the Gram eigenvectors, orthonormalised in order so that the
  // coefficients below are orthogonal projections (a direction of a zero eigenvalue that
  // Gram-Schmidt leaves with no new part is dropped: it adds nothing to the span).
  Eigen::MatrixXd dirs(d, rank);
  for (int r = 0; r < rank; ++r) {
    Eigen::VectorXd a = x.transpose() * eig.vectors.col(r);
    const double first = a.norm();
    for (int q = 0; q < r; ++q) a -= dirs.col(q).dot(a) * dirs.col(q);
    const double left = a.norm();
    if (first > 0 && left > 1e-10 * first)
      dirs.col(r) = a / left;
    else
      dirs.col(r).setZero();
  }
  const Eigen::MatrixXd coef = x * dirs;  // n x K

  SvdState s;
  s.mode = Mode::kTexelPca;
  s.sampling = sampling_of(btf);
  s.rank = rank;
  s.discarded = discarded;
  s.total = total;
  s.mean.resize(static_cast<std::size_t>(d));
  for (Eigen::Index i = 0; i < d; ++i)
    s.mean[static_cast<std::size_t>(i)] = static_cast<float>(mean[i]);
  s.components.resize(static_cast<std::size_t>(d) * static_cast<std::size_t>(rank));
  for (int r = 0; r < rank; ++r)
    for (Eigen::Index i = 0; i < d; ++i)
      s.components[static_cast<std::size_t>(r) * static_cast<std::size_t>(d) +
                   static_cast<std::size_t>(i)] = static_cast<float>(dirs(i, r));
  s.coefficients.resize(static_cast<std::size_t>(n) * static_cast<std::size_t>(rank));
  for (int t = 0; t < n; ++t)
    for (int r = 0; r < rank; ++r)
      s.coefficients[static_cast<std::size_t>(t) * static_cast<std::size_t>(rank) +
                     static_cast<std::size_t>(r)] = static_cast<float>(coef(t, r));
  return s;
}

}  // namespace prt::svd
