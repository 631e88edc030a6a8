// k-means: recovery of well-separated clusters, dense/sparse agreement, determinism in the seed
// and the thread count, monotone error, weights as multiplicities, empty-cluster re-seeding.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/numeric/kmeans.h"
#include "prtlab/numeric/row_set.h"

namespace prt {
namespace {

constexpr std::uint64_t kSeed = 20240611;

struct Labelled {
  Eigen::MatrixXd points;
  std::vector<int> truth;
};

// Clusters of unequal sizes around centres 100 apart, unit noise: any sane k-means separates them.
Labelled separated_clusters(int k, int dims, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  std::vector<Eigen::VectorXd> centres;
  for (int c = 0; c < k; ++c) {
    Eigen::VectorXd v(dims);
    for (int d = 0; d < dims; ++d) v[d] = g(rng);
    centres.push_back(100.0 * v.normalized() * (1.0 + c));
  }
  Labelled out;
  std::vector<Eigen::VectorXd> rows;
  for (int c = 0; c < k; ++c) {
    for (int i = 0; i < 20 + 7 * c; ++i) {
      Eigen::VectorXd p = centres[c];
      for (int d = 0; d < dims; ++d) p[d] += g(rng);
      rows.push_back(p);
      out.truth.push_back(c);
    }
  }
  // Interleave so that no algorithm can profit from the generation order.
  std::vector<std::size_t> order(rows.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), rng);
  out.points.resize(static_cast<Eigen::Index>(rows.size()), dims);
  std::vector<int> truth(rows.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    out.points.row(static_cast<Eigen::Index>(i)) = rows[order[i]].transpose();
    truth[i] = out.truth[order[i]];
  }
  out.truth = truth;
  return out;
}

// True when the two labellings are the same partition (equal up to renaming the labels).
bool same_partition(const std::vector<int>& truth, const std::vector<std::uint32_t>& found) {
  std::map<int, std::uint32_t> forward;
  std::map<std::uint32_t, int> backward;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    auto [f, fnew] = forward.emplace(truth[i], found[i]);
    auto [b, bnew] = backward.emplace(found[i], truth[i]);
    if (f->second != found[i] || b->second != truth[i]) return false;
  }
  return true;
}

double direct_squared_error(const Eigen::MatrixXd& x, const KMeansResult& r,
                            const std::vector<double>& w = {}) {
  double s = 0.0;
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const double d = (x.row(i) - r.centroids.row(r.assignments[i])).squaredNorm();
    s += (w.empty() ? 1.0 : w[i]) * d;
  }
  return s;
}

class KMeansInits : public ::testing::TestWithParam<KMeansInit> {};

TEST_P(KMeansInits, RecoversWellSeparatedClusters) {
  for (const int k : {2, 3, 5, 7}) {
    for (std::uint64_t seed = kSeed; seed < kSeed + 4; ++seed) {
      const Labelled data = separated_clusters(k, 8, seed);
      KMeansOptions o;
      o.clusters = k;
      o.init = GetParam();
      o.seed = seed;
      const KMeansResult r = kmeans(RowSet::dense(data.points), o);
      EXPECT_TRUE(same_partition(data.truth, r.assignments))
          << "k = " << k << ", seed = " << seed << ", squared error " << r.squared_error;
      ASSERT_EQ(r.centroids.rows(), k);
      for (int c = 0; c < k; ++c) EXPECT_GT(r.counts[c], 0u) << "seed " << seed;
    }
  }
}

TEST_P(KMeansInits, SquaredErrorNeverIncreasesAndMatchesTheAssignment) {
  std::mt19937_64 rng(kSeed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd x(500, 6);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    for (Eigen::Index j = 0; j < x.cols(); ++j) x(i, j) = u(rng) + (i % 3) * 0.5;
  }
  std::vector<double> w(500);
  for (double& wi : w) wi = 0.5 + u(rng) * 0.4;
  for (const bool weighted : {false, true}) {
    KMeansOptions o;
    o.clusters = 12;
    o.init = GetParam();
    o.seed = kSeed;
    if (weighted) o.weights = w;
    const KMeansResult r = kmeans(RowSet::dense(x), o);
    ASSERT_GE(r.squared_error_history.size(), 2u);
    // The expanded distance rounds at the scale of ||x||^2, so that is the scale of the slack.
    const double slack = 1e-12 * x.squaredNorm();
    for (std::size_t t = 1; t < r.squared_error_history.size(); ++t) {
      EXPECT_LE(r.squared_error_history[t], r.squared_error_history[t - 1] + slack)
          << "iteration " << t << ", seed " << kSeed << ", weighted " << weighted;
    }
    const double direct = direct_squared_error(x, r, weighted ? w : std::vector<double>{});
    EXPECT_NEAR(r.squared_error, direct, 1e-10 * direct) << "seed " << kSeed;
    EXPECT_EQ(r.squared_error, r.squared_error_history.back());
  }
}

INSTANTIATE_TEST_SUITE_P(Numeric, KMeansInits,
                         ::testing::Values(KMeansInit::kLbgSplitting, KMeansInit::kPlusPlus));

// Sparse rows with cluster-specific supports, as rows of T look: few non-zeros of many columns.
struct SparseData {
  std::size_t cols = 600;
  std::vector<std::uint32_t> offsets{0};
  std::vector<std::uint16_t> columns16;
  std::vector<std::uint32_t> columns32;
  std::vector<std::uint8_t> counts;  // value = count * scale
  double scale = 1.0 / 64.0;
  Eigen::MatrixXd dense;
};

SparseData sparse_clusters(std::uint64_t seed) {
  SparseData s;
  std::mt19937_64 rng(seed);
  const int rows = 400;
  s.dense = Eigen::MatrixXd::Zero(rows, static_cast<Eigen::Index>(s.cols));
  for (int i = 0; i < rows; ++i) {
    const int cluster = static_cast<int>(rng() % 6);
    std::vector<std::uint32_t> cols;
    while (cols.size() < 12) {
      // Mostly the cluster's own 60 columns, sometimes anywhere.
      const std::uint32_t c = rng() % 5 == 0
                                  ? static_cast<std::uint32_t>(rng() % s.cols)
                                  : static_cast<std::uint32_t>(cluster * 100 + rng() % 60);
      if (std::find(cols.begin(), cols.end(), c) == cols.end()) cols.push_back(c);
    }
    std::sort(cols.begin(), cols.end());
    for (const std::uint32_t c : cols) {
      const auto count = static_cast<std::uint8_t>(1 + rng() % 64);
      s.columns16.push_back(static_cast<std::uint16_t>(c));
      s.columns32.push_back(c);
      s.counts.push_back(count);
      s.dense(i, c) = static_cast<double>(count) * s.scale;
    }
    s.offsets.push_back(static_cast<std::uint32_t>(s.columns32.size()));
  }
  return s;
}

void expect_identical(const KMeansResult& a, const KMeansResult& b, const std::string& what) {
  EXPECT_EQ(a.assignments, b.assignments) << what;
  ASSERT_EQ(a.centroids.rows(), b.centroids.rows()) << what;
  ASSERT_EQ(a.centroids.cols(), b.centroids.cols()) << what;
  EXPECT_EQ(0, std::memcmp(a.centroids.data(), b.centroids.data(),
                           sizeof(double) * static_cast<std::size_t>(a.centroids.size())))
      << what << ": centroids differ, largest difference "
      << (a.centroids - b.centroids).cwiseAbs().maxCoeff();
  EXPECT_EQ(a.squared_error, b.squared_error) << what;
  EXPECT_EQ(a.iterations, b.iterations) << what;
  EXPECT_EQ(a.counts, b.counts) << what;
}

TEST(KMeans, SparseAndDensePathsGiveTheSameResult) {
  const SparseData s = sparse_clusters(kSeed);
  std::vector<double> values(s.counts.size());
  std::vector<float> fvalues(s.counts.size());
  for (std::size_t e = 0; e < s.counts.size(); ++e) {
    values[e] = s.counts[e] * s.scale;
    fvalues[e] = static_cast<float>(values[e]);  // exact: count / 64
  }
  const RowSet dense = RowSet::dense(s.dense);
  const RowSet sparse_u8 =
      RowSet::csr(s.cols, s.offsets, std::span<const std::uint16_t>(s.columns16),
                  std::span<const std::uint8_t>(s.counts), s.scale);
  const RowSet sparse_double =
      RowSet::csr(s.cols, s.offsets, std::span<const std::uint32_t>(s.columns32),
                  std::span<const double>(values));
  const RowSet sparse_float =
      RowSet::csr(s.cols, s.offsets, std::span<const std::uint32_t>(s.columns32),
                  std::span<const float>(fvalues));
  for (const KMeansInit init : {KMeansInit::kLbgSplitting, KMeansInit::kPlusPlus}) {
    KMeansOptions o;
    o.clusters = 6;
    o.init = init;
    o.seed = kSeed;
    const KMeansResult d = kmeans(dense, o);
    // Every path walks a row in increasing column order, so the sums are the same to the bit.
    expect_identical(d, kmeans(sparse_u8, o),
                     "u16 columns, u8 counts, seed " + std::to_string(kSeed));
    expect_identical(d, kmeans(sparse_double, o), "u32 columns, double values");
    expect_identical(d, kmeans(sparse_float, o), "u32 columns, float values");
    const double direct = direct_squared_error(s.dense, d);
    EXPECT_NEAR(d.squared_error, direct, 1e-10 * direct);
  }
}

TEST(KMeans, SameSeedIsBitIdenticalAndThreadCountDoesNotMatter) {
  const SparseData s = sparse_clusters(kSeed + 1);
  const RowSet sparse = RowSet::csr(s.cols, s.offsets, std::span<const std::uint16_t>(s.columns16),
                                    std::span<const std::uint8_t>(s.counts), s.scale);
  for (const KMeansInit init : {KMeansInit::kLbgSplitting, KMeansInit::kPlusPlus}) {
    KMeansOptions o;
    o.clusters = 9;
    o.init = init;
    o.seed = kSeed;
    const KMeansResult a = kmeans(sparse, o);
    expect_identical(a, kmeans(sparse, o), "same seed " + std::to_string(kSeed));
    {
      tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
      expect_identical(a, kmeans(sparse, o), "one thread, seed " + std::to_string(kSeed));
    }
    // Other seeds may give other (equally valid) clusterings; the seed must at least be used.
    bool any_differs = false;
    for (std::uint64_t seed = kSeed + 1; seed < kSeed + 6; ++seed) {
      o.seed = seed;
      const KMeansResult b = kmeans(sparse, o);
      EXPECT_EQ(b.centroids.rows(), 9);
      any_differs = any_differs || b.centroids != a.centroids;
    }
    EXPECT_TRUE(any_differs) << "five other seeds all gave the clustering of seed " << kSeed;
  }
}

TEST(KMeans, IntegerWeightsActAsRepeatedPoints) {
  std::mt19937_64 rng(kSeed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixXd x(60, 3);
  for (Eigen::Index i = 0; i < x.size(); ++i) x.data()[i] = u(rng);
  std::vector<double> w(60);
  std::vector<Eigen::Index> repeated;
  for (Eigen::Index i = 0; i < 60; ++i) {
    w[i] = static_cast<double>(1 + rng() % 3);
    for (int r = 0; r < w[i]; ++r) repeated.push_back(i);
  }
  Eigen::MatrixXd xr(static_cast<Eigen::Index>(repeated.size()), 3);
  for (std::size_t r = 0; r < repeated.size(); ++r) xr.row(r) = x.row(repeated[r]);
  Eigen::MatrixXd start = x.topRows(4);
  KMeansOptions o;
  o.weights = w;
  const KMeansResult weighted = kmeans_from(RowSet::dense(x), start, o);
  o.weights = {};
  const KMeansResult plain = kmeans_from(RowSet::dense(xr), start, o);
  EXPECT_LT((weighted.centroids - plain.centroids).cwiseAbs().maxCoeff(), 1e-12)
      << "seed " << kSeed;
  EXPECT_NEAR(weighted.squared_error, plain.squared_error, 1e-12 * plain.squared_error);
}

TEST(KMeans, EmptyClusterIsReseededFromTheFarthestPoint) {
  Eigen::MatrixXd x(4, 1);
  x << 0.0, 0.1, 0.2, 10.0;
  Eigen::MatrixXd start(2, 1);
  start << 0.1, 1000.0;  // the second centroid attracts nothing
  const KMeansResult r = kmeans_from(RowSet::dense(x), start, KMeansOptions{});
  // The first update empties centroid 1 and moves it onto 10, the point farthest from the mean.
  EXPECT_NEAR(r.centroids(0, 0), 0.1, 1e-15);
  EXPECT_EQ(r.centroids(1, 0), 10.0);
  EXPECT_EQ(r.counts, (std::vector<std::size_t>{3, 1}));
  EXPECT_NEAR(r.squared_error, 0.02, 1e-15);
}

TEST(KMeans, KEqualToThePointCountPutsEveryPointAlone) {
  Eigen::MatrixXd x(5, 2);
  x << 0, 0, 1, 0, 0, 1, 5, 5, 5, 6;
  for (const KMeansInit init : {KMeansInit::kLbgSplitting, KMeansInit::kPlusPlus}) {
    KMeansOptions o;
    o.clusters = 5;
    o.init = init;
    o.seed = kSeed;
    const KMeansResult r = kmeans(RowSet::dense(x), o);
    EXPECT_EQ(r.counts, std::vector<std::size_t>(5, 1));
    EXPECT_LT(r.squared_error, 1e-24);
  }
}

TEST(KMeans, NearestCentroidsMatchesBruteForce) {
  std::mt19937_64 rng(kSeed);
  std::normal_distribution<double> g;
  Eigen::MatrixXd x(100, 5), c(7, 5);
  for (Eigen::Index i = 0; i < x.size(); ++i) x.data()[i] = g(rng);
  for (Eigen::Index i = 0; i < c.size(); ++i) c.data()[i] = g(rng);
  const NearestCentroids n = nearest_centroids(RowSet::dense(x), c);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    Eigen::Index best = 0;
    const double d = (c.rowwise() - x.row(i)).rowwise().squaredNorm().minCoeff(&best);
    EXPECT_EQ(n.assignments[i], static_cast<std::uint32_t>(best)) << "point " << i;
    EXPECT_NEAR(n.squared_distances[i], d, 1e-12 * (1.0 + x.row(i).squaredNorm()));
  }
}

TEST(KMeans, RejectsBadParameters) {
  Eigen::MatrixXd x = Eigen::MatrixXd::Random(10, 2);
  const RowSet set = RowSet::dense(x);
  KMeansOptions o;
  o.clusters = 0;
  EXPECT_THROW(kmeans(set, o), ParameterError);
  o.clusters = 11;
  EXPECT_THROW(kmeans(set, o), ParameterError);
  o.clusters = 2;
  std::vector<double> short_w(9, 1.0), negative(10, 1.0), zero(10, 0.0);
  negative[3] = -1.0;
  o.weights = short_w;
  EXPECT_THROW(kmeans(set, o), ParameterError);
  o.weights = negative;
  EXPECT_THROW(kmeans(set, o), ParameterError);
  o.weights = zero;
  EXPECT_THROW(kmeans(set, o), ParameterError);
  o.weights = {};
  EXPECT_THROW(kmeans_from(set, Eigen::MatrixXd::Zero(2, 3), o), ParameterError);
}

}  // namespace
}  // namespace prt
