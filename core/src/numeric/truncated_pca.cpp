#include "prtlab/numeric/truncated_pca.h"

#include <Spectra/SymEigsSolver.h>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <type_traits>

#include "numeric/row_access.h"
#include "prtlab/base/error.h"
#include "prtlab/numeric/row_products.h"
#include "prtlab/numeric/symmetric_eigen.h"

namespace prt {

namespace {

using numeric_detail::axpy;
using numeric_detail::dot;

template <class A>
struct IsDense : std::false_type {};
template <class T>
struct IsDense<numeric_detail::DenseRowAccess<T>> : std::true_type {};

template <class A>
Eigen::VectorXd row_mean(const A& a) {
  Eigen::VectorXd mu = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(a.cols()));
  for (std::size_t i = 0; i < a.rows(); ++i) axpy(a, i, 1.0, mu.data());
  return mu / static_cast<double>(a.rows());
}

// ||x_i - mu||^2 summed entry by entry over the stored entries, plus the mean's own mass on the
// columns the row does not store: no ||x||^2 - 2 x.mu + ||mu||^2 cancellation.
template <class A>
double centred_squared_norm(const A& a, std::size_t i, const Eigen::VectorXd& mu, double mu_sq) {
  double stored = 0.0;
  double mu_stored = 0.0;
  a.for_each(i, [&](std::size_t j, double x) {
    const double d = x - mu[static_cast<Eigen::Index>(j)];
    stored += d * d;
    mu_stored += mu[static_cast<Eigen::Index>(j)] * mu[static_cast<Eigen::Index>(j)];
  });
  return stored + std::max(0.0, mu_sq - mu_stored);
}

// tbb::parallel_for over blocks of 128 rows, instantiated outside any template: clang 14 (the
// fuzz preset) does not emit tbb's task for a lambda in apply_c<A> and the library fails to link.
void parallel_row_blocks(std::size_t rows,
                         const std::function<void(std::size_t, std::size_t)>& body) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows, 128),
                    [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
}

// Y = C Q for a row-major block Q (n x l): row i of Y is x_i Q - mu^T Q.
template <class A>
RowMajorMatrixXd apply_c(const A& a, const RowMajorMatrixXd& q, const Eigen::VectorXd& mu) {
  const Eigen::RowVectorXd mu_q = mu.transpose() * q;
  RowMajorMatrixXd y(static_cast<Eigen::Index>(a.rows()), q.cols());
  const auto l = static_cast<std::size_t>(q.cols());
  const double* qd = q.data();
  parallel_row_blocks(a.rows(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i != end; ++i) {
      y.row(static_cast<Eigen::Index>(i)) = -mu_q;
      double* yi = y.data() + i * l;
      a.for_each(i, [&](std::size_t j, double x) { axpy_f64(x, qd + j * l, yi, l); });
    }
  });
  return y;
}

// Z = C^T Y = sum_i x_i^T y_i - mu (1^T Y). Sequential, so the sum order is fixed.
template <class A>
RowMajorMatrixXd apply_ct(const A& a, const RowMajorMatrixXd& y, const Eigen::VectorXd& mu) {
  RowMajorMatrixXd z = -mu * y.colwise().sum();
  const auto l = static_cast<std::size_t>(y.cols());
  double* zd = z.data();
  for (std::size_t i = 0; i < a.rows(); ++i) {
    const double* yi = y.data() + i * l;
    a.for_each(i, [&](std::size_t j, double x) { axpy_f64(x, yi, zd + j * l, l); });
  }
  return z;
}

// Modified Gram-Schmidt, twice, over the first `valid` columns; columns that are (numerically)
// dependent on their predecessors, and all columns from `valid` on, are replaced by unit vectors
// e_t orthogonalised the same way (the first that keeps half its length, else the longest), so
// the result always has orthonormal columns.
void orthonormalise(Eigen::MatrixXd& u, Eigen::Index valid) {
  const Eigen::Index n = u.rows();
  Eigen::Index next_unit = 0;
  auto project_out = [&](Eigen::VectorXd& v, Eigen::Index upto) {
    for (int pass = 0; pass < 2; ++pass) {
      for (Eigen::Index p = 0; p < upto; ++p) v -= u.col(p).dot(v) * u.col(p);
    }
  };
  for (Eigen::Index j = 0; j < u.cols(); ++j) {
    Eigen::VectorXd v = u.col(j);
    const double before = v.norm();
    if (j < valid && before > 0.0) {
      project_out(v, j);
      if (v.norm() > 0.5 * before) {
        u.col(j) = v.normalized();
        continue;
      }
    }
    for (;; ++next_unit) {
      if (next_unit >= n) {
        // No unit vector kept half its length: the complement is spread over many axes (a basis
        // completed to the whole space). The residuals' squared norms sum to the complement's
        // dimension, so the longest is at least sqrt((n - j) / n).
        PRT_CHECK(j < n, "orthonormalise: {} columns in dimension {}", u.cols(), n);
        double longest = -1.0;
        for (Eigen::Index t = 0; t < n; ++t) {
          Eigen::VectorXd w = Eigen::VectorXd::Unit(n, t);
          project_out(w, j);
          if (w.norm() > longest) {
            longest = w.norm();
            v = w;
          }
        }
        break;
      }
      v = Eigen::VectorXd::Unit(n, next_unit);
      project_out(v, j);
      if (v.norm() > 0.5) break;
    }
    ++next_unit;
    u.col(j) = v.normalized();
  }
}

void fix_signs(Eigen::MatrixXd& u) {
  for (Eigen::Index j = 0; j < u.cols(); ++j) {
    Eigen::Index arg = 0;
    u.col(j).cwiseAbs().maxCoeff(&arg);
    if (u(arg, j) < 0.0) u.col(j) *= -1.0;
  }
}

template <class A>
void gram_path(const A& a, const Eigen::VectorXd& mu, Eigen::Index k, TruncatedPca& out) {
  const auto m = static_cast<Eigen::Index>(a.rows());
  const auto n = static_cast<Eigen::Index>(a.cols());
  Eigen::MatrixXd g(m, m);
  Eigen::MatrixXd centred;  // dense input only: the rows, centred, for one GEMM
  if constexpr (IsDense<A>::value) {
    centred.resize(m, n);
    for (Eigen::Index i = 0; i < m; ++i) {
      centred.row(i) = -mu.transpose();
      a.for_each(static_cast<std::size_t>(i),
                 [&](std::size_t j, double x) { centred(i, static_cast<Eigen::Index>(j)) += x; });
    }
    g.noalias() = centred * centred.transpose();
  } else {
    // (x_j - mu).w_i with w_i = x_i - mu dense: the sparse row costs its non-zeros.
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, m, 8), [&](const auto& r) {
      Eigen::VectorXd w(n);
      for (Eigen::Index i = r.begin(); i != r.end(); ++i) {
        w = -mu;
        axpy(a, static_cast<std::size_t>(i), 1.0, w.data());
        const double w_mu = w.dot(mu);
        for (Eigen::Index j = 0; j <= i; ++j) {
          g(i, j) = dot(a, static_cast<std::size_t>(j), w.data()) - w_mu;
        }
      }
    });
    for (Eigen::Index i = 0; i < m; ++i) {
      for (Eigen::Index j = i + 1; j < m; ++j) g(i, j) = g(j, i);
    }
  }
  const Eigen::Index have = std::min(k, m);
  // Eigen's solver, not LAPACK's: these solves run in parallel over clusters, and the serial
  // OpenBLAS is entered by one thread at a time (docs/build-options.md, PRTLAB_LAPACK).
  const SymmetricEigen eig = top_symmetric_eigen_eigen(g, have);
  const double top = have > 0 ? std::max(0.0, eig.values[0]) : 0.0;
  // An eigenvalue this small carries no direction that survives rounding; its component comes
  // from the completion instead.
  const double floor = top * static_cast<double>(m) * std::numeric_limits<double>::epsilon();
  out.components = Eigen::MatrixXd::Zero(n, k);
  out.eigenvalues = Eigen::VectorXd::Zero(k);
  Eigen::Index valid = 0;
  for (Eigen::Index j = 0; j < have; ++j) {
    const double lambda = eig.values[j];
    if (!(lambda > floor)) break;
    const Eigen::VectorXd v = eig.vectors.col(j);
    Eigen::VectorXd u;
    if constexpr (IsDense<A>::value) {
      u = centred.transpose() * v;
    } else {
      u = -mu * v.sum();
      for (Eigen::Index i = 0; i < m; ++i) axpy(a, static_cast<std::size_t>(i), v[i], u.data());
    }
    out.components.col(j) = u / std::sqrt(lambda);
    out.eigenvalues[j] = lambda;
    valid = j + 1;
  }
  orthonormalise(out.components, valid);
}

template <class A>
void subspace_path(const A& a, const Eigen::VectorXd& mu, Eigen::Index k,
                   const TruncatedPcaOptions& o, TruncatedPca& out) {
  const auto m = static_cast<Eigen::Index>(a.rows());
  const auto n = static_cast<Eigen::Index>(a.cols());
  const Eigen::Index l = std::min({k + o.oversampling, n, m});
  std::mt19937_64 rng(o.seed);
  Eigen::MatrixXd start(n, l);
  const Eigen::Index warm = o.start.rows() == n ? std::min(l, o.start.cols()) : 0;
  if (warm > 0) start.leftCols(warm) = o.start.leftCols(warm);
  for (Eigen::Index c = warm; c < l; ++c) {
    for (Eigen::Index r = 0; r < n; ++r) {
      start(r, c) = static_cast<double>(rng() >> 11) * 0x1.0p-52 - 1.0;
    }
  }
  auto orth = [&](const Eigen::MatrixXd& z) -> RowMajorMatrixXd {
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(z);
    return qr.householderQ() * Eigen::MatrixXd::Identity(n, l);
  };
  RowMajorMatrixXd q = orth(start);
  RowMajorMatrixXd y;
  Eigen::VectorXd theta;
  // Rayleigh-Ritz on span(Q): from the SVD of C Q = P Sigma V^T the Ritz vectors are Q V with
  // values sigma^2, and C (Q V) = (C Q) V is reused by the next multiplication by C^T.
  auto rayleigh_ritz = [&]() {
    const RowMajorMatrixXd b = apply_c(a, q, mu);
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(b, Eigen::ComputeThinV);
    const Eigen::MatrixXd& v = svd.matrixV();
    q = q * v;
    y = b * v;
    theta = svd.singularValues().array().square();
  };
  rayleigh_ritz();
  int it = 0;
  // The iteration cap is tested first: a capped run (CPCA's passes) needs no residual.
  while (it < o.max_iterations) {
    const RowMajorMatrixXd z = apply_ct(a, y, mu);  // S Q
    double worst = 0.0;
    for (Eigen::Index j = 0; j < k; ++j) {
      worst = std::max(worst, (z.col(j) - theta[j] * q.col(j)).norm());
    }
    if (worst <= o.tolerance * theta[0]) break;
    q = orth(z);
    rayleigh_ritz();
    ++it;
  }
  out.iterations = it;
  out.components = q.leftCols(k);
  out.eigenvalues = theta.head(k);
  // Ritz vectors are orthonormal to rounding; one more pass makes that exact-ish for callers
  // that rely on U^T U = I.
  orthonormalise(out.components, k);
}

// S x = C^T (C x) applied through the rows, for Spectra: C x is one sparse dot per row, C^T y a
// sequential sum so that the result does not depend on the thread count.
template <class A>
class ScatterOperator {
 public:
  using Scalar = double;
  ScatterOperator(const A& a, const Eigen::VectorXd& mu) : a_(a), mu_(mu), y_(a.rows()) {}
  Eigen::Index rows() const { return static_cast<Eigen::Index>(a_.cols()); }
  Eigen::Index cols() const { return rows(); }
  void perform_op(const double* x_in, double* y_out) const {
    const Eigen::Map<const Eigen::VectorXd> x(x_in, rows());
    const double mu_x = mu_.dot(x);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, a_.rows(), 256), [&](const auto& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) y_[i] = dot(a_, i, x_in) - mu_x;
    });
    Eigen::Map<Eigen::VectorXd> out(y_out, rows());
    out = -mu_ * y_.sum();
    for (std::size_t i = 0; i < a_.rows(); ++i) axpy(a_, i, y_[i], y_out);
  }

 private:
  const A& a_;
  const Eigen::VectorXd& mu_;
  mutable Eigen::VectorXd y_;
};

template <class A>
void lanczos_path(const A& a, const Eigen::VectorXd& mu, Eigen::Index k,
                  const TruncatedPcaOptions& o, TruncatedPca& out) {
  const auto n = static_cast<Eigen::Index>(a.cols());
  ScatterOperator<A> op(a, mu);
  const Eigen::Index ncv = std::min(n, std::max<Eigen::Index>(2 * k + 1, k + 20));
  Spectra::SymEigsSolver<ScatterOperator<A>> eigs(op, k, ncv);
  // A seeded start vector: Spectra's own init() is seeded too, but the seed is not ours.
  std::mt19937_64 rng(o.seed);
  Eigen::VectorXd v0(n);
  for (Eigen::Index r = 0; r < n; ++r) v0[r] = static_cast<double>(rng() >> 11) * 0x1.0p-52 - 1.0;
  if (o.start.rows() == n && o.start.cols() > 0) v0 += o.start.rowwise().sum();
  eigs.init(v0.data());
  eigs.compute(Spectra::SortRule::LargestAlge, std::max(1, o.max_iterations),
               std::max(o.tolerance, 1e-14));
  if (eigs.info() != Spectra::CompInfo::Successful) {
    throw Error(fmt::format(
        "truncated_pca: Spectra's Lanczos did not converge to {} eigenpairs within {} restarts", k,
        o.max_iterations));
  }
  out.iterations = static_cast<int>(eigs.num_iterations());
  out.components = eigs.eigenvectors();
  out.eigenvalues = eigs.eigenvalues();
  orthonormalise(out.components, k);
}

}  // namespace

TruncatedPca truncated_pca(const RowSet& rows, const TruncatedPcaOptions& options) {
  const std::size_t m = rows.rows();
  const std::size_t n = rows.cols();
  if (m == 0) throw ParameterError("truncated_pca: there are no rows");
  if (options.components < 1 || static_cast<std::size_t>(options.components) > n) {
    throw ParameterError(
        fmt::format("truncated_pca: {} components asked of dimension {}", options.components, n));
  }
  if (options.oversampling < 0 || options.max_iterations < 0 || !(options.tolerance >= 0.0)) {
    throw ParameterError("truncated_pca: oversampling, max_iterations and tolerance must be >= 0");
  }
  const auto k = static_cast<Eigen::Index>(options.components);
  PcaMethod method = options.method;
  if (method == PcaMethod::kAuto) {
    method = (m <= options.gram_max_rows && m <= n) || m < static_cast<std::size_t>(k)
                 ? PcaMethod::kGram
                 : PcaMethod::kSubspace;
  }
  if (options.start.size() > 0 && static_cast<std::size_t>(options.start.rows()) != n) {
    throw ParameterError(fmt::format("truncated_pca: the start block has {} rows, the rows {}",
                                     options.start.rows(), n));
  }
  if (method == PcaMethod::kLanczos && static_cast<std::size_t>(k) >= n) {
    throw ParameterError(fmt::format(
        "truncated_pca: Lanczos needs fewer components than the dimension ({} of {})", k, n));
  }
  if ((method == PcaMethod::kSubspace || method == PcaMethod::kLanczos) &&
      m < static_cast<std::size_t>(k)) {
    throw ParameterError(fmt::format(
        "truncated_pca: the subspace iteration needs at least {} rows (it has {}); use kGram", k,
        m));
  }
  return numeric_detail::visit_rows(rows, [&](const auto& a) {
    TruncatedPca out;
    out.method = method;
    out.mean = options.center ? row_mean(a) : Eigen::VectorXd::Zero(static_cast<Eigen::Index>(n));
    const double mu_sq = out.mean.squaredNorm();
    for (std::size_t i = 0; i < m; ++i) {
      out.total_squared_error += centred_squared_norm(a, i, out.mean, mu_sq);
    }
    if (method == PcaMethod::kGram) {
      gram_path(a, out.mean, k, out);
    } else if (method == PcaMethod::kLanczos) {
      lanczos_path(a, out.mean, k, options, out);
    } else {
      subspace_path(a, out.mean, k, options, out);
    }
    fix_signs(out.components);
    out.eigenvalues = out.eigenvalues.cwiseMax(0.0);
    out.singular_values = out.eigenvalues.cwiseSqrt();
    out.residual_squared_error = std::max(0.0, out.total_squared_error - out.eigenvalues.sum());
    return out;
  });
}

namespace {

void check_pca_matches(const RowSet& rows, const TruncatedPca& pca, const char* who) {
  if (static_cast<std::size_t>(pca.mean.size()) != rows.cols() ||
      pca.components.rows() != pca.mean.size()) {
    throw ParameterError(fmt::format("{}: the PCA has dimension {} but the rows have {}", who,
                                     pca.mean.size(), rows.cols()));
  }
}

}  // namespace

Eigen::MatrixXd pca_coefficients(const RowSet& rows, const TruncatedPca& pca) {
  check_pca_matches(rows, pca, "pca_coefficients");
  return numeric_detail::visit_rows(rows, [&](const auto& a) -> Eigen::MatrixXd {
    const RowMajorMatrixXd u = pca.components;
    const RowMajorMatrixXd y = apply_c(a, u, pca.mean);
    return y;
  });
}

Eigen::VectorXd pca_row_squared_errors(const RowSet& rows, const TruncatedPca& pca) {
  check_pca_matches(rows, pca, "pca_row_squared_errors");
  const Eigen::MatrixXd coef = pca_coefficients(rows, pca);
  return numeric_detail::visit_rows(rows, [&](const auto& a) {
    const double mu_sq = pca.mean.squaredNorm();
    Eigen::VectorXd e(static_cast<Eigen::Index>(a.rows()));
    for (std::size_t i = 0; i < a.rows(); ++i) {
      const auto ii = static_cast<Eigen::Index>(i);
      e[ii] =
          std::max(0.0, centred_squared_norm(a, i, pca.mean, mu_sq) - coef.row(ii).squaredNorm());
    }
    return e;
  });
}

}  // namespace prt
