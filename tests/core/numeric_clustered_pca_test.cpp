// Clustered PCA (Sloan 2003) against independent dense computations: one cluster is plain PCA
// (a dense SVD's discarded energy), the reported weights and error are the explicit projection,
// the error never grows with the vector count, iterative beats static and adaptive keeps the
// weight budget while beating iterative on clusters of unequal complexity. Also the row
// products (a dense product) and the affine codebook error (an explicit reconstruction).
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/numeric/clustered_pca.h"
#include "prtlab/numeric/row_products.h"
#include "prtlab/numeric/row_set.h"

namespace prt {
namespace {

constexpr std::uint64_t kSeed = 20261202;

struct Csr {
  std::size_t cols = 0;
  std::vector<std::uint32_t> offsets{0};
  std::vector<std::uint16_t> columns;
  std::vector<std::uint8_t> counts;  // values = counts / 4, as T stores them
  Eigen::MatrixXd dense;
  RowSet set() const {
    return RowSet::csr(cols, offsets, std::span<const std::uint16_t>(columns),
                       std::span<const std::uint8_t>(counts), 0.25);
  }
};

Csr to_csr(const Eigen::MatrixXd& counts) {
  Csr s;
  s.cols = static_cast<std::size_t>(counts.cols());
  s.dense = counts * 0.25;
  for (Eigen::Index i = 0; i < counts.rows(); ++i) {
    for (Eigen::Index j = 0; j < counts.cols(); ++j) {
      if (counts(i, j) != 0) {
        s.columns.push_back(static_cast<std::uint16_t>(j));
        s.counts.push_back(static_cast<std::uint8_t>(counts(i, j)));
      }
    }
    s.offsets.push_back(static_cast<std::uint32_t>(s.counts.size()));
  }
  return s;
}

// Sparse non-negative rows drawn from `groups` groups, each with its own support of `support`
// columns and a low-dimensional family of profiles of dimension `dims[g]` (so groups differ in
// complexity), quantised to counts 0..8 like T's values.
Csr grouped_rows(int rows, int cols, int support, const std::vector<int>& dims,
                 std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int groups = static_cast<int>(dims.size());
  std::vector<std::vector<int>> supports(groups);
  std::vector<Eigen::MatrixXd> profiles(groups);
  for (int g = 0; g < groups; ++g) {
    for (int j = 0; j < support; ++j) supports[g].push_back(static_cast<int>(rng() % cols));
    profiles[g] = Eigen::MatrixXd(dims[g] + 1, support);
    for (Eigen::Index i = 0; i < profiles[g].size(); ++i) profiles[g].data()[i] = u(rng);
  }
  Eigen::MatrixXd counts = Eigen::MatrixXd::Zero(rows, cols);
  for (int i = 0; i < rows; ++i) {
    const int g = static_cast<int>(rng() % groups);
    Eigen::RowVectorXd v = profiles[g].row(0) * 4.0;
    for (int d = 1; d <= dims[g]; ++d) v += (u(rng) * 2.0 - 1.0) * 2.0 * profiles[g].row(d);
    for (int j = 0; j < support; ++j) {
      const double c = std::clamp(std::round(v[j]), 0.0, 8.0);
      counts(i, supports[g][j]) = std::max(counts(i, supports[g][j]), c);
    }
  }
  return to_csr(counts);
}

// The explicit reconstruction of every point from the result, in double.
Eigen::MatrixXd reconstruct(const ClusteredPca& r, Eigen::Index rows, Eigen::Index cols) {
  Eigen::MatrixXd x(rows, cols);
  for (Eigen::Index p = 0; p < rows; ++p) {
    const CpcaCluster& c = r.clusters[r.assignments[static_cast<std::size_t>(p)]];
    Eigen::VectorXd v = c.mean;
    for (int i = 0; i < c.k(); ++i) {
      v += r.weights[r.weight_offsets[static_cast<std::size_t>(p)] + static_cast<std::size_t>(i)] *
           c.components.col(i);
    }
    x.row(p) = v.transpose();
  }
  return x;
}

void expect_consistent(const ClusteredPca& r, const Csr& s, const char* what) {
  const auto m = s.dense.rows();
  ASSERT_EQ(r.assignments.size(), static_cast<std::size_t>(m)) << what;
  const Eigen::MatrixXd x = reconstruct(r, m, s.dense.cols());
  const double direct = (x - s.dense).squaredNorm();
  EXPECT_NEAR(r.squared_error, direct, 1e-9 * s.dense.squaredNorm()) << what;
  EXPECT_NEAR(r.total_squared_norm, s.dense.squaredNorm(), 1e-12 * s.dense.squaredNorm());
  // Each point's weights are its projection on its cluster's orthonormal vectors.
  for (const CpcaCluster& c : r.clusters) {
    if (c.k() == 0) continue;
    const Eigen::MatrixXd g = c.components.transpose() * c.components;
    EXPECT_LT((g - Eigen::MatrixXd::Identity(c.k(), c.k())).cwiseAbs().maxCoeff(), 1e-10) << what;
  }
  for (Eigen::Index p = 0; p < m; p += 7) {
    const CpcaCluster& c = r.clusters[r.assignments[static_cast<std::size_t>(p)]];
    const Eigen::VectorXd w = c.components.transpose() * (s.dense.row(p).transpose() - c.mean);
    for (int i = 0; i < c.k(); ++i) {
      EXPECT_NEAR(r.weights[r.weight_offsets[static_cast<std::size_t>(p)] + i], w[i], 1e-10)
          << what << ": point " << p;
    }
  }
  // Cluster means are the means of their members (the optimal offset for any subspace).
  std::vector<Eigen::VectorXd> sums(r.clusters.size(), Eigen::VectorXd::Zero(s.dense.cols()));
  std::vector<int> counts(r.clusters.size(), 0);
  for (Eigen::Index p = 0; p < m; ++p) {
    sums[r.assignments[static_cast<std::size_t>(p)]] += s.dense.row(p).transpose();
    ++counts[r.assignments[static_cast<std::size_t>(p)]];
  }
  for (std::size_t c = 0; c < r.clusters.size(); ++c) {
    EXPECT_EQ(r.clusters[c].count, static_cast<std::size_t>(counts[c])) << what;
    if (counts[c] > 0) {
      EXPECT_LT((sums[c] / counts[c] - r.clusters[c].mean).cwiseAbs().maxCoeff(), 1e-12) << what;
    }
  }
}

TEST(RowProducts, MatchTheDenseProduct) {
  const Csr s = grouped_rows(120, 90, 12, {2, 3}, kSeed);
  std::mt19937_64 rng(kSeed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  RowMajorMatrixXd b(90, 7);
  for (Eigen::Index i = 0; i < b.size(); ++i) b.data()[i] = u(rng);
  const Eigen::MatrixXd expected = s.dense * b;
  const RowMajorMatrixXd y = multiply_rows(s.set(), b);
  EXPECT_LT((y - expected).cwiseAbs().maxCoeff(), 1e-13 * (1 + expected.cwiseAbs().maxCoeff()));
  const RowMajorMatrixXf bf = b.cast<float>();
  const RowMajorMatrixXf yf = multiply_rows(s.set(), bf);
  const Eigen::MatrixXd expected_f = s.dense * bf.cast<double>();
  // Float accumulation over at most 12 terms: within 12 eps_f of the sum of magnitudes.
  const Eigen::MatrixXd magnitude = s.dense.cwiseAbs() * bf.cast<double>().cwiseAbs();
  EXPECT_TRUE(((yf.cast<double>() - expected_f).cwiseAbs().array() <=
               (12 * 6e-8 * magnitude.array() + 1e-30))
                  .all());
  // The dense storage of the same rows gives the same product.
  const RowMajorMatrixXd yd = multiply_rows(RowSet::dense(s.dense), b);
  EXPECT_LT((yd - y).cwiseAbs().maxCoeff(), 1e-13 * (1 + expected.cwiseAbs().maxCoeff()));
  EXPECT_LT((row_squared_norms(s.set()) - s.dense.rowwise().squaredNorm()).cwiseAbs().maxCoeff(),
            1e-12);
  EXPECT_THROW(multiply_rows(s.set(), RowMajorMatrixXd(89, 3)), ParameterError);
}

TEST(ClusteredPca, OneClusterIsPcaAndMatchesTheDenseSvd) {
  const Csr s = grouped_rows(200, 60, 15, {3, 2, 4}, kSeed + 1);
  const Eigen::MatrixXd c = s.dense.rowwise() - s.dense.colwise().mean();
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(c).singularValues();
  for (const CpcaMethod method : {CpcaMethod::kStatic, CpcaMethod::kIterative}) {
    for (const int k : {0, 1, 3, 6}) {
      ClusteredPcaOptions o;
      o.clusters = 1;
      o.components = k;
      o.method = method;
      o.seed = kSeed;
      o.pca_tolerance = 1e-12;
      const ClusteredPca r = clustered_pca(s.set(), o);
      const double discarded = sv.tail(sv.size() - k).squaredNorm();
      EXPECT_NEAR(r.squared_error, discarded, 1e-9 * sv.squaredNorm())
          << "k = " << k << ", method " << static_cast<int>(method);
      for (int i = 0; i < k; ++i) {
        EXPECT_NEAR(r.clusters[0].eigenvalues[i], sv[i] * sv[i], 1e-9 * sv[0] * sv[0]);
      }
      expect_consistent(r, s, "one cluster");
    }
  }
}

TEST(ClusteredPca, ErrorNeverGrowsWithTheVectorCount) {
  const Csr s = grouped_rows(400, 80, 14, {1, 2, 3, 5, 2, 4}, kSeed + 2);
  double previous = s.dense.squaredNorm();
  for (int k = 0; k <= 6; ++k) {
    ClusteredPcaOptions o;
    o.clusters = 6;
    o.components = k;
    o.method = CpcaMethod::kIterative;
    o.seed = kSeed;
    const ClusteredPca r = clustered_pca(s.set(), o);
    expect_consistent(r, s, "iterative");
    EXPECT_LE(r.squared_error, previous * (1 + 1e-9)) << "n' = " << k;
    EXPECT_EQ(r.weight_count(), static_cast<std::uint64_t>(400 * k));
    previous = r.squared_error;
  }
}

TEST(ClusteredPca, IterativeBeatsStaticAndAdaptiveBeatsIterativeWithinTheBudget) {
  // Groups of very different complexity, so that equal vector counts per cluster waste weights.
  const Csr s = grouped_rows(900, 120, 20, {1, 1, 1, 6, 7, 1, 5, 1}, kSeed + 3);
  ClusteredPcaOptions o;
  o.clusters = 8;
  o.components = 3;
  o.seed = kSeed;
  o.method = CpcaMethod::kStatic;
  const ClusteredPca st = clustered_pca(s.set(), o);
  o.method = CpcaMethod::kIterative;
  const ClusteredPca it = clustered_pca(s.set(), o);
  o.method = CpcaMethod::kAdaptive;
  const ClusteredPca ad = clustered_pca(s.set(), o);
  expect_consistent(st, s, "static");
  expect_consistent(it, s, "iterative");
  expect_consistent(ad, s, "adaptive");
  EXPECT_LE(it.squared_error, st.squared_error);
  EXPECT_LT(ad.squared_error, it.squared_error);
  // Weights and vectors together stay within what the iterative result stores.
  std::uint64_t ad_values = 0;
  for (const CpcaCluster& c : ad.clusters) ad_values += (c.count + 120) * c.k();
  EXPECT_LE(ad_values, static_cast<std::uint64_t>(900 + 8 * 120) * 3);
  int lo = 1 << 30, hi = 0;
  for (const CpcaCluster& c : ad.clusters) {
    lo = std::min(lo, c.k());
    hi = std::max(hi, c.k());
  }
  EXPECT_LT(lo, hi) << "adaptive gave every cluster the same count";
  // The history is what it says: passes in order, the final one the result.
  ASSERT_FALSE(it.history.empty());
  EXPECT_EQ(it.history.front().stage, "vq");
  EXPECT_EQ(it.history.back().stage, "final");
  EXPECT_DOUBLE_EQ(it.history.back().squared_error, it.squared_error);
  EXPECT_GT(it.times.classify_passes, 0);
  EXPECT_GT(it.times.classify_flops, 0.0);
}

CpcaCluster cluster_with(std::size_t count, std::vector<double> eigenvalues) {
  CpcaCluster c;
  c.count = count;
  c.eigenvalues = Eigen::Map<const Eigen::VectorXd>(eigenvalues.data(),
                                                    static_cast<Eigen::Index>(eigenvalues.size()));
  return c;
}

// Section 4.3 of the paper: rank every vector by D_i^2 / m_k and add vectors in that order until
// the per-point weights reach the budget. Three clusters of 100, 50 and 10 points, n' = 1: the
// budget is 160 weights. Rates: cluster 2 (m = 10) 8, 5, 3, 1; cluster 1 (m = 50) 6, 2; cluster 0
// (m = 100) 1.5, 0.5. In order: 2#0 (10 weights), 1#0 (60), 2#1 (70), 2#2 (80), 1#1 (130), then
// 0#0 would need 230 > 160: the allocation ends there, so 2#3 (rate 1, 10 weights) is not added.
TEST(ClusteredPca, SloanRuleAllocatesByErrorPerPointUntilTheWeightBudget) {
  const std::vector<CpcaCluster> clusters = {cluster_with(100, {150, 50}),
                                             cluster_with(50, {300, 100}),
                                             cluster_with(10, {80, 50, 30, 10})};
  EXPECT_EQ(adaptive_allocation(clusters, 1, CpcaAdaptiveRule::kSloan, 1.0, 25),
            (std::vector<int>{0, 2, 3}));
  // The weight cost and the dimension do not enter the paper's rule.
  EXPECT_EQ(adaptive_allocation(clusters, 1, CpcaAdaptiveRule::kSloan, 0.25, 6144),
            (std::vector<int>{0, 2, 3}));
  // prtlab's rule with the same costs (dim 0: a vector costs its m_c weights) skips 0#0 and
  // still fits 2#3 (140 weights).
  EXPECT_EQ(adaptive_allocation(clusters, 1, CpcaAdaptiveRule::kStorage, 1.0, 0),
            (std::vector<int>{0, 2, 4}));
  // With 25 floats per vector the costs are 125, 75, 35 and the budget 235: rates 1#0 4,
  // 2#0 2.29, 2#1 1.43, 1#1 1.33 (220 in all), then nothing else fits.
  EXPECT_EQ(adaptive_allocation(clusters, 1, CpcaAdaptiveRule::kStorage, 1.0, 25),
            (std::vector<int>{0, 2, 2}));
  // n' = 2: budget 320 weights. After 1#1 (130): 0#0 (230), 2#3 (240), 0#1 (340 > 320) ends it.
  EXPECT_EQ(adaptive_allocation(clusters, 2, CpcaAdaptiveRule::kSloan, 1.0, 25),
            (std::vector<int>{1, 2, 4}));
  // An empty cluster gets nothing, whatever its eigenvalues.
  const std::vector<CpcaCluster> with_empty = {cluster_with(0, {1e9}), cluster_with(10, {5, 4})};
  EXPECT_EQ(adaptive_allocation(with_empty, 1, CpcaAdaptiveRule::kSloan, 1.0, 25),
            (std::vector<int>{0, 1}));
}

// The paper's rule inside the engine: the weights never exceed m n', and with converged PCA
// updates the result is a consistent model like every other method's.
TEST(ClusteredPca, SloanRuleKeepsThePerPointWeightBudget) {
  const Csr s = grouped_rows(900, 120, 20, {1, 1, 1, 6, 7, 1, 5, 1}, kSeed + 3);
  ClusteredPcaOptions o;
  o.clusters = 8;
  o.components = 3;
  o.seed = kSeed;
  o.method = CpcaMethod::kIterative;
  const ClusteredPca it = clustered_pca(s.set(), o);
  o.method = CpcaMethod::kAdaptive;
  o.adaptive_rule = CpcaAdaptiveRule::kSloan;
  for (const bool converged : {false, true}) {
    SCOPED_TRACE(converged ? "converged updates" : "warm updates");
    o.converge_every_update = converged;
    const ClusteredPca ad = clustered_pca(s.set(), o);
    expect_consistent(ad, s, "adaptive, sloan");
    EXPECT_LE(ad.weight_count(), std::uint64_t{900 * 3});
    EXPECT_LT(ad.squared_error, it.squared_error);
    int lo = 1 << 30, hi = 0;
    for (const CpcaCluster& c : ad.clusters) {
      lo = std::min(lo, c.k());
      hi = std::max(hi, c.k());
    }
    EXPECT_LT(lo, hi) << "the paper's rule gave every cluster the same count";
  }
}

TEST(ClusteredPca, IsDeterministicAndMatchesOnDenseInput) {
  const Csr s = grouped_rows(300, 50, 10, {2, 3, 1}, kSeed + 4);
  ClusteredPcaOptions o;
  o.clusters = 4;
  o.components = 2;
  o.method = CpcaMethod::kAdaptive;
  o.seed = 9;
  const ClusteredPca a = clustered_pca(s.set(), o);
  const ClusteredPca b = clustered_pca(s.set(), o);
  EXPECT_EQ(a.assignments, b.assignments);
  EXPECT_EQ(a.weights, b.weights);
  const ClusteredPca d = clustered_pca(RowSet::dense(s.dense), o);
  EXPECT_EQ(a.assignments, d.assignments);
  EXPECT_NEAR(a.squared_error, d.squared_error, 1e-9 * s.dense.squaredNorm());
}

TEST(ClusteredPca, AffineCodebookErrorIsTheExplicitReconstructionError) {
  const Csr s = grouped_rows(150, 40, 8, {2, 1, 3}, kSeed + 5);
  ClusteredPcaOptions o;
  o.clusters = 3;
  o.components = 2;
  o.method = CpcaMethod::kAdaptive;
  const ClusteredPca r = clustered_pca(s.set(), o);
  // Store the model as a renderer would: float representatives, weights rounded to 1/64.
  std::vector<std::uint32_t> first{0};
  for (const CpcaCluster& c : r.clusters) first.push_back(first.back() + 1 + c.k());
  RowMajorMatrixXd reps(first.back(), 40);
  for (std::size_t c = 0; c < r.clusters.size(); ++c) {
    reps.row(first[c]) = r.clusters[c].mean.transpose().cast<float>().cast<double>();
    for (int i = 0; i < r.clusters[c].k(); ++i)
      reps.row(first[c] + 1 + i) =
          r.clusters[c].components.col(i).transpose().cast<float>().cast<double>();
  }
  std::vector<double> w(r.weights.size());
  for (std::size_t i = 0; i < w.size(); ++i) w[i] = std::round(r.weights[i] * 64) / 64;
  double direct = 0.0;
  for (Eigen::Index p = 0; p < s.dense.rows(); ++p) {
    const std::uint32_t c = r.assignments[static_cast<std::size_t>(p)];
    Eigen::RowVectorXd v = reps.row(first[c]);
    for (std::uint32_t i = 0; i + 1 < first[c + 1] - first[c]; ++i)
      v += w[r.weight_offsets[static_cast<std::size_t>(p)] + i] * reps.row(first[c] + 1 + i);
    direct += (v - s.dense.row(p)).squaredNorm();
  }
  const double e =
      affine_codebook_squared_error(s.set(), r.assignments, reps, first, w, r.weight_offsets);
  EXPECT_NEAR(e, direct, 1e-10 * s.dense.squaredNorm());
  EXPECT_GT(e, r.squared_error) << "rounding the weights must cost something";
  std::vector<std::uint32_t> bad = r.assignments;
  bad[0] = 3;
  EXPECT_THROW(affine_codebook_squared_error(s.set(), bad, reps, first, w, r.weight_offsets),
               ParameterError);
}

TEST(ClusteredPca, RejectsBadParameters) {
  const Csr s = grouped_rows(10, 20, 5, {1}, kSeed);
  ClusteredPcaOptions o;
  o.clusters = 11;
  EXPECT_THROW(clustered_pca(s.set(), o), ParameterError);
  o.clusters = 0;
  EXPECT_THROW(clustered_pca(s.set(), o), ParameterError);
  o.clusters = 2;
  o.components = 21;
  EXPECT_THROW(clustered_pca(s.set(), o), ParameterError);
  o.components = -1;
  EXPECT_THROW(clustered_pca(s.set(), o), ParameterError);
}

}  // namespace
}  // namespace prt
