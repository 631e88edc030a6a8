// ELBG: escapes the local minimum Lloyd iterations stay in, never raises the distortion, rejects
// bad input.
#include <gtest/gtest.h>

#include <random>
#include <set>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/numeric/elbg.h"
#include "prtlab/numeric/kmeans.h"
#include "prtlab/numeric/row_set.h"

namespace prt {
namespace {

constexpr std::size_t kDims = 12;

// Three unit-noise blobs of 60 points, centred at 0, 20 e_0 and 20 e_1.
std::vector<float> three_blobs() {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g;
  std::vector<float> x;
  for (int b = 0; b < 3; ++b)
    for (int i = 0; i < 60; ++i)
      for (std::size_t d = 0; d < kDims; ++d) {
        double v = g(rng);
        if (b == 1 && d == 0) v += 20;
        if (b == 2 && d == 1) v += 20;
        x.push_back(static_cast<float>(v));
      }
  return x;
}

TEST(Elbg, EscapesTheLocalMinimumLloydKeeps) {
  const std::vector<float> x = three_blobs();
  // Two codewords inside blob 0, one between blobs 1 and 2: a fixed point of Lloyd iterations.
  Eigen::MatrixXd start = Eigen::MatrixXd::Zero(3, kDims);
  start(0, 2) = -0.5;
  start(1, 2) = 0.5;
  start(2, 0) = 10;
  start(2, 1) = 10;
  KMeansOptions k;
  k.max_iterations = 50;
  const KMeansResult lloyd = kmeans_from(RowSet::dense(x, 180, kDims), start, k);
  ElbgOptions o;
  const ElbgResult e = elbg_from(x, 180, kDims, start, o);
  // Lloyd keeps blobs 1 and 2 together: about 2 x 60 x 200 of distortion; apart it is ~2,160.
  EXPECT_GT(lloyd.squared_error, 20000.0);
  EXPECT_LT(e.squared_error, 3000.0);
  EXPECT_GE(e.shifts_accepted, 1);
  for (int b = 0; b < 3; ++b) {
    std::set<std::uint32_t> ids;
    for (int i = 0; i < 60; ++i) ids.insert(e.assignments[static_cast<std::size_t>(b * 60 + i)]);
    EXPECT_EQ(ids.size(), 1u) << "blob " << b << " is split";
  }
  EXPECT_EQ(std::set<std::uint32_t>(e.assignments.begin(), e.assignments.end()).size(), 3u);
}

TEST(Elbg, DistortionNeverIncreases) {
  std::mt19937_64 rng(11);
  std::normal_distribution<float> g;
  const std::size_t n = 400, dims = 30;
  std::vector<float> x(n * dims);
  for (float& v : x) v = g(rng) * g(rng);  // heavy-tailed, so that cells differ in utility
  for (int clusters : {3, 8, 25}) {
    ElbgOptions o;
    o.clusters = clusters;
    o.seed = 5;
    o.tolerance = 0;
    const ElbgResult e = elbg(x, n, dims, o);
    double previous = e.initial_squared_error;
    for (double h : e.squared_error_history) {
      EXPECT_LE(h, previous * (1 + 1e-12)) << clusters << " clusters";
      previous = h;
    }
    EXPECT_LE(e.squared_error, e.initial_squared_error * (1 + 1e-12));
    // The reported distortion is the distortion of the returned codebook and assignment.
    double direct = 0;
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t d = 0; d < dims; ++d) {
        const double diff = x[i * dims + d] - e.centroids(e.assignments[i], static_cast<int>(d));
        direct += diff * diff;
      }
    EXPECT_NEAR(direct, e.squared_error, 1e-9 * direct);
    std::size_t total = 0;
    for (std::size_t c : e.counts) total += c;
    EXPECT_EQ(total, n);
  }
}

TEST(Elbg, RejectsBadInput) {
  const std::vector<float> x(10 * 3, 1.0f);
  ElbgOptions o;
  o.clusters = 11;
  EXPECT_THROW(elbg(x, 10, 3, o), ParameterError);
  o.clusters = 2;
  EXPECT_THROW(elbg(x, 9, 3, o), ParameterError);
  std::vector<float> bad = x;
  bad[4] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(elbg(bad, 10, 3, o), ParameterError);
  EXPECT_THROW(elbg_from(x, 10, 3, Eigen::MatrixXd::Zero(2, 4), o), ParameterError);
}

}  // namespace
}  // namespace prt
