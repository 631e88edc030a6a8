// Exact relight L* = T L: the float CSR product against a dense double product, one thread
// against many, Eigen's sparse product against ours, both column-index widths.
#include "prtlab/transfer/exact_relight.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "prtlab/base/error.h"

namespace prt {
namespace {

constexpr std::uint64_t kSeed = 20240612;

// A random matrix with the structure of T: per vertex block, each column used at most once,
// in a random row, with a random count in 1..s^2; some columns empty.
TransferMatrix random_transfer(std::size_t vertices, int m, int n, int s, double density,
                               std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uniform_int_distribution<int> row_of(0, m - 1), count_of(1, s * s);
  std::vector<std::uint32_t> offsets{0}, cols;
  std::vector<std::uint8_t> counts;
  std::vector<std::vector<std::pair<std::uint32_t, std::uint8_t>>> rows(
      static_cast<std::size_t>(m));
  for (std::size_t v = 0; v < vertices; ++v) {
    for (auto& r : rows) r.clear();
    for (int k = 0; k < n; ++k)
      if (u(rng) < density)
        rows[row_of(rng)].push_back(
            {static_cast<std::uint32_t>(k), static_cast<std::uint8_t>(count_of(rng))});
    for (const auto& r : rows) {
      for (const auto& [c, x] : r) {
        cols.push_back(c);
        counts.push_back(x);
      }
      offsets.push_back(static_cast<std::uint32_t>(cols.size()));
    }
  }
  return TransferMatrix::from_csr(vertices, m, n, s, offsets, cols, counts);
}

std::vector<Rgb> random_light(int n, std::mt19937_64& rng) {
  std::uniform_real_distribution<float> u(0.0f, 2.0f);
  std::vector<Rgb> l(static_cast<std::size_t>(n));
  for (auto& x : l) x = {u(rng), u(rng), u(rng)};
  return l;
}

// Dense reference: expand T to a dense double matrix and multiply.
std::vector<Vec3d> dense_product(const TransferMatrix& t, const std::vector<Rgb>& light) {
  std::vector<double> dense(t.rows() * t.cols(), 0.0);
  for (std::size_t row = 0; row < t.rows(); ++row)
    for (std::uint32_t i = t.row_offsets()[row]; i < t.row_offsets()[row + 1]; ++i)
      dense[row * t.cols() + t.column(i)] =
          t.counts()[i] / (t.supersampling() * t.supersampling() * 1.0);
  std::vector<Vec3d> out(t.rows(), Vec3d(0.0));
  for (std::size_t row = 0; row < t.rows(); ++row)
    for (std::size_t k = 0; k < t.cols(); ++k)
      out[row] += dense[row * t.cols() + k] * Vec3d(light[k]);
  return out;
}

double rel_error(std::span<const Rgb> a, const std::vector<Vec3d>& ref) {
  double num = 0.0, den = 0.0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const Vec3d d = Vec3d(a[i]) - ref[i];
    num += glm::dot(d, d);
    den += glm::dot(ref[i], ref[i]);
  }
  return std::sqrt(num / den);
}

struct Shape {
  std::size_t vertices;
  int m, n, s;
  double density;
};

class ExactRelight : public ::testing::TestWithParam<Shape> {};

TEST_P(ExactRelight, MatchesDenseDoubleProduct) {
  const Shape shape = GetParam();
  std::mt19937_64 rng(kSeed);
  const TransferMatrix t =
      random_transfer(shape.vertices, shape.m, shape.n, shape.s, shape.density, rng);
  ASSERT_GT(t.nnz(), 0u);
  EXPECT_EQ(t.narrow_columns(), shape.n <= 65536);
  const auto light = random_light(shape.n, rng);
  const auto ref = dense_product(t, light);

  std::vector<Rgb> many(t.rows()), one(t.rows()), eigen(t.rows());
  relight_exact(t, light, many);
  relight_exact(t, light, one, RelightThreads::kOne);
  const double err = rel_error(many, ref);
  EXPECT_LT(err, 1e-6) << "seed " << kSeed;
  // The per-row arithmetic does not depend on the partition into tasks.
  EXPECT_TRUE(std::equal(many.begin(), many.end(), one.begin()));

  const auto dbl = relight_exact_double(t, light);
  double max_diff = 0.0;
  for (std::size_t i = 0; i < ref.size(); ++i)
    max_diff = std::max(max_diff, glm::length(dbl[i] - ref[i]));
  EXPECT_LT(max_diff, 1e-9);

  const EigenSparseTransfer eig(t);
  eig.relight(light, eigen);
  EXPECT_LT(rel_error(eigen, ref), 1e-6);

  const LocalRadiance lr = relight_exact(t, light);
  EXPECT_EQ(lr.basis, RadianceBasis::kPixel);
  EXPECT_EQ(lr.dim, shape.m);
  EXPECT_EQ(lr.vertices, shape.vertices);
  EXPECT_TRUE(std::equal(lr.values.begin(), lr.values.end(), many.begin()));
}

INSTANTIATE_TEST_SUITE_P(Shapes, ExactRelight,
                         ::testing::Values(Shape{40, 16, 96, 2, 0.5},
                                           Shape{25, 64, 6 * 16 * 16, 2, 0.3},
                                           Shape{7, 9, 6 * 8 * 8, 3, 0.9},
                                           Shape{3, 4, 70000, 2, 0.01}));  // 32-bit columns

TEST(ExactRelight, RejectsMismatchedShapes) {
  std::mt19937_64 rng(kSeed);
  const TransferMatrix t = random_transfer(2, 4, 24, 2, 0.5, rng);
  std::vector<Rgb> light(23), out(t.rows());
  EXPECT_THROW(relight_exact(t, light, out), ParameterError);
  light.resize(24);
  out.resize(t.rows() + 1);
  EXPECT_THROW(relight_exact(t, light, out), ParameterError);
  EXPECT_THROW(EigenSparseTransfer(t).relight(light, out), ParameterError);
}

}  // namespace
}  // namespace prt
