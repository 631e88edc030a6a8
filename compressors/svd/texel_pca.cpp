#include "svd/texel_pca.h"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "prtlab/base/error.h"

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
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(gram.selfadjointView<Eigen::Lower>());
  if (eig.info() != Eigen::Success)
    throw Error(fmt::format(
        "material svd: the texel Gram eigensolver did not converge for BTF '{}'", btf.material()));
  // Ascending eigenvalues: the K leading are the last K.
  const Eigen::VectorXd& lambda = eig.eigenvalues();
  double discarded = 0;
  for (Eigen::Index i = 0; i < n - rank; ++i) discarded += std::max(lambda[i], 0.0);

  // Principal directions from the Gram eigenvectors, orthonormalised in order so that the
  // coefficients below are orthogonal projections (a direction of a zero eigenvalue that
  // Gram-Schmidt leaves with no new part is dropped: it adds nothing to the span).
  Eigen::MatrixXd dirs(d, rank);
  for (int r = 0; r < rank; ++r) {
    Eigen::VectorXd a = x.transpose() * eig.eigenvectors().col(n - 1 - r);
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
