// Truncated PCA against Eigen's dense eigen-decomposition of the explicit scatter matrix, for the
// Gram and the subspace path, dense and CSR input; residual error, coefficients, rank-deficient
// input, subsets and determinism.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/numeric/row_set.h"
#include "prtlab/numeric/truncated_pca.h"

namespace prt {
namespace {

constexpr std::uint64_t kSeed = 20240612;
constexpr double kEps = std::numeric_limits<double>::epsilon();

struct Reference {
  Eigen::VectorXd eigenvalues;  // decreasing
  Eigen::MatrixXd vectors;      // matching columns
  Eigen::VectorXd mean;
};

Reference reference(const Eigen::MatrixXd& x, bool center = true) {
  Reference r;
  r.mean =
      center ? Eigen::VectorXd(x.colwise().mean().transpose()) : Eigen::VectorXd::Zero(x.cols());
  const Eigen::MatrixXd c = x.rowwise() - r.mean.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(c.transpose() * c);
  r.eigenvalues = eig.eigenvalues().reverse();
  r.vectors = eig.eigenvectors().rowwise().reverse();
  return r;
}

// Random rows with the scatter spectrum decaying geometrically by `decay` per direction, plus an
// offset so that the implicit centring matters.
Eigen::MatrixXd decaying_rows(Eigen::Index m, Eigen::Index n, double decay, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  Eigen::MatrixXd a(m, n), b(n, n);
  for (Eigen::Index i = 0; i < a.size(); ++i) a.data()[i] = g(rng);
  for (Eigen::Index i = 0; i < b.size(); ++i) b.data()[i] = g(rng);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(b);
  const Eigen::MatrixXd basis = qr.householderQ();
  Eigen::VectorXd s(n);
  for (Eigen::Index j = 0; j < n; ++j) s[j] = std::pow(decay, static_cast<double>(j));
  Eigen::MatrixXd x = a * s.asDiagonal() * basis.transpose();
  x.rowwise() += Eigen::RowVectorXd::Constant(n, 3.0);
  return x;
}

struct Csr {
  std::size_t cols = 0;
  std::vector<std::uint32_t> offsets{0};
  std::vector<std::uint16_t> columns;
  std::vector<double> values;
  Eigen::MatrixXd dense;
  RowSet set() const {
    return RowSet::csr(cols, offsets, std::span<const std::uint16_t>(columns),
                       std::span<const double>(values));
  }
};

// Sparse rows whose column j carries weight decay^j, so the scatter spectrum has clear gaps.
Csr sparse_rows(int m, int n, int per_row, double decay, std::uint64_t seed) {
  Csr s;
  s.cols = static_cast<std::size_t>(n);
  s.dense = Eigen::MatrixXd::Zero(m, n);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.5, 1.5);
  for (int i = 0; i < m; ++i) {
    std::vector<int> cols;
    while (static_cast<int>(cols.size()) < per_row) {
      const int c = static_cast<int>(rng() % static_cast<std::uint64_t>(n));
      if (std::find(cols.begin(), cols.end(), c) == cols.end()) cols.push_back(c);
    }
    std::sort(cols.begin(), cols.end());
    for (const int c : cols) {
      const double v = u(rng) * std::pow(decay, c);
      s.columns.push_back(static_cast<std::uint16_t>(c));
      s.values.push_back(v);
      s.dense(i, c) = v;
    }
    s.offsets.push_back(static_cast<std::uint32_t>(s.values.size()));
  }
  return s;
}

// sin of the largest principal angle between span(u) and span(v), both orthonormal.
double subspace_sine(const Eigen::MatrixXd& u, const Eigen::MatrixXd& v) {
  const Eigen::MatrixXd off = u - v * (v.transpose() * u);
  return Eigen::JacobiSVD<Eigen::MatrixXd>(off).singularValues()[0];
}

// Compares with the reference. Both computations are backward stable, so each eigenvalue is
// within c (m + n) eps lambda_max of the exact one; the subspace iteration adds its stopping
// residual r <= tol lambda_max, worth r^2 / gap on an eigenvalue. By Davis-Kahan, the kept
// subspace moves by at most (perturbation) / gap, gap = lambda_{k-1} - lambda_k.
void expect_matches(const TruncatedPca& p, const Reference& r, int k, double tolerance,
                    Eigen::Index m, const std::string& what) {
  const double top = r.eigenvalues[0];
  const double backward = 64.0 * static_cast<double>(m + r.mean.size()) * kEps * top;
  const double residual = tolerance * top;
  const double gap = r.eigenvalues[k - 1] - r.eigenvalues[k];
  ASSERT_GT(gap, 0.0) << what;
  ASSERT_EQ(p.components.cols(), k) << what;
  EXPECT_LT((p.mean - r.mean).cwiseAbs().maxCoeff(), 1e-13 * (1.0 + r.mean.cwiseAbs().maxCoeff()))
      << what;
  for (int j = 0; j < k; ++j) {
    const double err = std::abs(p.eigenvalues[j] - r.eigenvalues[j]);
    const double gap_j = std::min(j > 0 ? r.eigenvalues[j - 1] - r.eigenvalues[j] : top,
                                  r.eigenvalues[j] - r.eigenvalues[j + 1]);
    const double bound = backward + residual * residual / gap_j;
    EXPECT_LE(err, bound) << what << ": eigenvalue " << j << " relative error "
                          << err / r.eigenvalues[j] << " (bound " << bound / r.eigenvalues[j]
                          << ")";
    EXPECT_NEAR(p.singular_values[j], std::sqrt(p.eigenvalues[j]), 1e-15 * p.singular_values[0]);
  }
  const double sine = subspace_sine(p.components, r.vectors.leftCols(k));
  const double sine_bound = (backward + residual) / gap;
  EXPECT_LE(sine, sine_bound) << what << ": subspace angle sine " << sine << ", bound "
                              << sine_bound;
  const Eigen::MatrixXd gram = p.components.transpose() * p.components;
  EXPECT_LT((gram - Eigen::MatrixXd::Identity(k, k)).cwiseAbs().maxCoeff(), 1e-13) << what;
  // The residual is what the discarded eigenvalues hold.
  const double discarded = r.eigenvalues.tail(r.eigenvalues.size() - k).sum();
  const double res_bound = static_cast<double>(r.eigenvalues.size()) * backward +
                           static_cast<double>(k) * residual * residual / gap;
  EXPECT_NEAR(p.residual_squared_error, discarded, res_bound + 1e-13 * r.eigenvalues.sum())
      << what << ": relative error " << std::abs(p.residual_squared_error - discarded) / discarded;
  EXPECT_NEAR(p.total_squared_error, r.eigenvalues.sum(), 1e-12 * r.eigenvalues.sum()) << what;
}

TEST(TruncatedPca, GramPathMatchesDenseEigenDecomposition) {
  const Eigen::MatrixXd x = decaying_rows(50, 120, 0.8, kSeed);
  TruncatedPcaOptions o;
  o.method = PcaMethod::kGram;
  for (const int k : {1, 4, 10}) {
    o.components = k;
    const TruncatedPca p = truncated_pca(RowSet::dense(x), o);
    EXPECT_EQ(p.method, PcaMethod::kGram);
    expect_matches(p, reference(x), k, 0.0, x.rows(),
                   "dense Gram, k = " + std::to_string(k) + ", seed " + std::to_string(kSeed));
  }
}

TEST(TruncatedPca, SubspacePathMatchesDenseEigenDecomposition) {
  const Eigen::MatrixXd x = decaying_rows(400, 60, 0.85, kSeed);
  TruncatedPcaOptions o;
  o.method = PcaMethod::kSubspace;
  o.seed = kSeed;
  for (const int k : {1, 5, 12}) {
    o.components = k;
    const TruncatedPca p = truncated_pca(RowSet::dense(x), o);
    EXPECT_EQ(p.method, PcaMethod::kSubspace);
    EXPECT_LT(p.iterations, o.max_iterations) << "did not converge";
    expect_matches(p, reference(x), k, o.tolerance, x.rows(),
                   "dense subspace, k = " + std::to_string(k) + ", seed " + std::to_string(kSeed));
  }
}

TEST(TruncatedPca, SparseInputMatchesOnBothPaths) {
  const Csr s = sparse_rows(300, 400, 30, 0.97, kSeed);
  const Reference r = reference(s.dense);
  for (const PcaMethod method : {PcaMethod::kGram, PcaMethod::kSubspace}) {
    TruncatedPcaOptions o;
    o.method = method;
    o.components = 8;
    o.seed = kSeed;
    const TruncatedPca p = truncated_pca(s.set(), o);
    EXPECT_LT(p.iterations, o.max_iterations) << "did not converge";
    expect_matches(p, r, 8, method == PcaMethod::kSubspace ? o.tolerance : 0.0, s.dense.rows(),
                   std::string("sparse ") + (method == PcaMethod::kGram ? "Gram" : "subspace") +
                       ", seed " + std::to_string(kSeed));
    // The same rows, dense, give the same decomposition.
    const TruncatedPca d = truncated_pca(RowSet::dense(s.dense), o);
    EXPECT_LT((d.components - p.components).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT((d.eigenvalues - p.eigenvalues).cwiseAbs().maxCoeff(), 1e-12 * r.eigenvalues[0]);
  }
}

TEST(TruncatedPca, CoefficientsAndRowErrorsMatchTheExplicitProjection) {
  const Csr s = sparse_rows(200, 150, 20, 0.95, kSeed + 1);
  TruncatedPcaOptions o;
  o.components = 6;
  const TruncatedPca p = truncated_pca(s.set(), o);
  const Eigen::MatrixXd c = s.dense.rowwise() - p.mean.transpose();
  const Eigen::MatrixXd expected = c * p.components;
  const Eigen::MatrixXd coef = pca_coefficients(s.set(), p);
  EXPECT_LT((coef - expected).cwiseAbs().maxCoeff(), 1e-13 * (1.0 + c.cwiseAbs().maxCoeff()));
  const Eigen::VectorXd errors = pca_row_squared_errors(s.set(), p);
  const Eigen::MatrixXd rest = c - coef * p.components.transpose();
  const Eigen::VectorXd direct = rest.rowwise().squaredNorm();
  EXPECT_LT((errors - direct).cwiseAbs().maxCoeff(), 1e-12 * c.squaredNorm());
  EXPECT_NEAR(errors.sum(), p.residual_squared_error, 1e-12 * p.total_squared_error);
}

TEST(TruncatedPca, MoreComponentsThanRankCompleteAnOrthonormalBasis) {
  const Eigen::MatrixXd x = decaying_rows(5, 30, 0.9, kSeed);  // centred rank 4
  TruncatedPcaOptions o;
  o.components = 9;
  const TruncatedPca p = truncated_pca(RowSet::dense(x), o);
  const Eigen::MatrixXd gram = p.components.transpose() * p.components;
  EXPECT_LT((gram - Eigen::MatrixXd::Identity(9, 9)).cwiseAbs().maxCoeff(), 1e-13);
  const Reference r = reference(x);
  for (int j = 4; j < 9; ++j) EXPECT_LE(p.eigenvalues[j], 1e-12 * r.eigenvalues[0]) << j;
  EXPECT_LE(p.residual_squared_error, 1e-12 * p.total_squared_error);
}

// Every component of a low-dimensional signal (k = n, as the adaptive CPCA of 25-D transfer
// vectors asks of a cluster with few points): the completion must reach the whole space even
// when the complement left is spread evenly over the axes, where no single unit vector keeps
// half of its length.
TEST(TruncatedPca, AllComponentsOfAFewRowsCompleteTheWholeSpace) {
  for (int m : {3, 8, 12, 20}) {
    for (std::uint64_t seed = 0; seed < 8; ++seed) {
      SCOPED_TRACE(fmt::format("{} rows, seed {}", m, seed));
      const Eigen::MatrixXd x = decaying_rows(m, 25, 0.8, kSeed + seed);
      TruncatedPcaOptions o;
      o.components = 25;
      const TruncatedPca p = truncated_pca(RowSet::dense(x), o);
      const Eigen::MatrixXd gram = p.components.transpose() * p.components;
      EXPECT_LT((gram - Eigen::MatrixXd::Identity(25, 25)).cwiseAbs().maxCoeff(), 1e-12);
      EXPECT_LE(p.residual_squared_error, 1e-12 * p.total_squared_error);
    }
  }
}

TEST(TruncatedPca, SubsetEqualsTheGatheredRows) {
  const Eigen::MatrixXd x = decaying_rows(100, 20, 0.8, kSeed);
  const std::vector<std::uint32_t> pick{3, 17, 17, 42, 5, 99, 60, 61, 62, 70, 71, 80, 1};
  Eigen::MatrixXd gathered(static_cast<Eigen::Index>(pick.size()), 20);
  for (std::size_t i = 0; i < pick.size(); ++i) gathered.row(i) = x.row(pick[i]);
  TruncatedPcaOptions o;
  o.components = 3;
  const TruncatedPca a = truncated_pca(RowSet::dense(x).subset(pick), o);
  const TruncatedPca b = truncated_pca(RowSet::dense(gathered), o);
  EXPECT_LT((a.components - b.components).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(a.residual_squared_error, b.residual_squared_error, 1e-12 * b.total_squared_error);
}

TEST(TruncatedPca, UncentredMatchesTheRawScatter) {
  const Eigen::MatrixXd x = decaying_rows(80, 25, 0.8, kSeed);
  TruncatedPcaOptions o;
  o.components = 4;
  o.center = false;
  for (const PcaMethod method : {PcaMethod::kGram, PcaMethod::kSubspace}) {
    o.method = method;
    const TruncatedPca p = truncated_pca(RowSet::dense(x), o);
    EXPECT_EQ(p.mean, Eigen::VectorXd::Zero(25));
    expect_matches(p, reference(x, false), 4, method == PcaMethod::kSubspace ? o.tolerance : 0.0,
                   x.rows(), "uncentred, seed " + std::to_string(kSeed));
  }
}

TEST(TruncatedPca, SameSeedIsBitIdentical) {
  const Csr s = sparse_rows(300, 200, 15, 0.97, kSeed);
  TruncatedPcaOptions o;
  o.components = 5;
  o.method = PcaMethod::kSubspace;
  o.seed = kSeed;
  const TruncatedPca a = truncated_pca(s.set(), o);
  const TruncatedPca b = truncated_pca(s.set(), o);
  ASSERT_EQ(a.components.size(), b.components.size());
  EXPECT_EQ(0, std::memcmp(a.components.data(), b.components.data(),
                           sizeof(double) * static_cast<std::size_t>(a.components.size())));
  EXPECT_EQ(a.eigenvalues, b.eigenvalues);
  EXPECT_EQ(a.iterations, b.iterations);
}

TEST(TruncatedPca, AutoPicksGramOnlyForFewRowsOfManyColumns) {
  TruncatedPcaOptions o;
  o.components = 2;
  o.gram_max_rows = 100;
  auto method = [&](Eigen::Index m, Eigen::Index n) {
    return truncated_pca(RowSet::dense(decaying_rows(m, n, 0.8, kSeed)), o).method;
  };
  EXPECT_EQ(method(100, 200), PcaMethod::kGram);
  EXPECT_EQ(method(101, 200), PcaMethod::kSubspace);
  EXPECT_EQ(method(50, 10), PcaMethod::kSubspace);  // the block spans R^10: exact at once
  o.components = 8;
  EXPECT_EQ(method(5, 10), PcaMethod::kGram);  // fewer rows than components
}

TEST(TruncatedPca, RejectsBadParameters) {
  const Eigen::MatrixXd x = decaying_rows(6, 10, 0.8, kSeed);
  TruncatedPcaOptions o;
  o.components = 0;
  EXPECT_THROW(truncated_pca(RowSet::dense(x), o), ParameterError);
  o.components = 11;
  EXPECT_THROW(truncated_pca(RowSet::dense(x), o), ParameterError);
  o.components = 8;
  o.method = PcaMethod::kSubspace;
  EXPECT_THROW(truncated_pca(RowSet::dense(x), o), ParameterError);
  o.components = 2;
  o.method = PcaMethod::kGram;
  const TruncatedPca p = truncated_pca(RowSet::dense(x), o);
  const Eigen::MatrixXd other = Eigen::MatrixXd::Zero(3, 9);
  EXPECT_THROW(pca_coefficients(RowSet::dense(other), p), ParameterError);
}

TEST(TruncatedPca, LanczosPathMatchesDenseEigenDecomposition) {
  const Csr s = sparse_rows(300, 400, 30, 0.97, kSeed + 7);
  const Reference r = reference(s.dense);
  TruncatedPcaOptions o;
  o.method = PcaMethod::kLanczos;
  o.seed = kSeed;
  for (const int k : {1, 8}) {
    o.components = k;
    const TruncatedPca p = truncated_pca(s.set(), o);
    EXPECT_EQ(p.method, PcaMethod::kLanczos);
    // Spectra stops when every Ritz value is within tol of converged, i.e. a residual of about
    // sqrt(tol) lambda_max in the worst case.
    expect_matches(p, r, k, std::sqrt(o.tolerance), s.dense.rows(),
                   "sparse Lanczos, k = " + std::to_string(k) + ", seed " + std::to_string(kSeed));
  }
  o.components = 400;
  EXPECT_THROW(truncated_pca(s.set(), o), ParameterError) << "Lanczos needs k < n";
}

// A warm start spans part of the answer: the result is the same decomposition, and since
// Rayleigh-Ritz sees the start columns, even one iteration captures at least their variance.
TEST(TruncatedPca, WarmStartKeepsAtLeastTheStartBlocksVariance) {
  const Eigen::MatrixXd x = decaying_rows(600, 80, 0.9, kSeed + 3);
  const Reference r = reference(x);
  TruncatedPcaOptions o;
  o.method = PcaMethod::kSubspace;
  o.components = 6;
  o.seed = kSeed;
  const TruncatedPca cold = truncated_pca(RowSet::dense(x), o);
  // A start that is the true top-4 subspace, slightly rotated.
  Eigen::MatrixXd start = r.vectors.leftCols(4);
  start.col(0) += 0.05 * r.vectors.col(20);
  o.start = start;
  const TruncatedPca warm = truncated_pca(RowSet::dense(x), o);
  expect_matches(warm, r, 6, o.tolerance, x.rows(), "warm start");
  // Started from the exact top-6 subspace, Rayleigh-Ritz meets the tolerance before iterating.
  o.start = r.vectors.leftCols(6);
  const TruncatedPca exact = truncated_pca(RowSet::dense(x), o);
  EXPECT_EQ(exact.iterations, 0);
  EXPECT_GT(cold.iterations, 0);
  o.start = start;
  o.max_iterations = 0;
  const TruncatedPca one = truncated_pca(RowSet::dense(x), o);
  const Eigen::MatrixXd c = x.rowwise() - r.mean.transpose();
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(start);
  const Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(x.cols(), 4);
  const double start_variance = (c * q).squaredNorm();
  EXPECT_GE((c * one.components).squaredNorm(), start_variance * (1 - 1e-12));
  o.start = Eigen::MatrixXd::Zero(79, 2);
  EXPECT_THROW(truncated_pca(RowSet::dense(x), o), ParameterError);
}

}  // namespace
}  // namespace prt
