// Real spherical harmonics: closed forms for l <= 2, an independent evaluation through
// std::assoc_legendre for every (l, m) up to order 10, the addition theorem, orthonormality
// under cubemap quadrature, and projection / evaluation.
#include "prtlab/sphere/spherical_harmonics.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "prtlab/base/error.h"

namespace prt {
namespace {

constexpr std::uint64_t kSeed = 31337;
constexpr int kN = sh_count(kMaxShOrder);

std::vector<Vec3d> test_directions(std::uint64_t seed, int count) {
  std::vector<Vec3d> ds = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  while (static_cast<int>(ds.size()) < count) {
    const Vec3d v{g(rng), g(rng), g(rng)};
    if (glm::length(v) > 1e-6) ds.push_back(glm::normalize(v));
  }
  return ds;
}

std::array<double, kN> eval(int order, const Vec3d& d) {
  std::array<double, kN> y{};
  sh_eval(order, d, y);
  return y;
}

TEST(SphericalHarmonics, IndexAndCount) {
  EXPECT_EQ(sh_count(5), 25);
  EXPECT_EQ(sh_count(kMaxShOrder), 100);
  EXPECT_EQ(sh_index(0, 0), 0);
  EXPECT_EQ(sh_index(1, -1), 1);
  EXPECT_EQ(sh_index(1, 1), 3);
  EXPECT_EQ(sh_index(2, -2), 4);
  EXPECT_EQ(sh_index(9, 9), 99);
}

TEST(SphericalHarmonics, ClosedFormsUpToBandTwo) {
  // The constants of Sloan, "Stupid spherical harmonics tricks" (2008), appendix A2. That
  // table keeps the Condon-Shortley phase; without it (our convention) every sign is +.
  const double c0 = 0.282094791773878, c1 = 0.488602511902920, c2 = 1.092548430592079,
               c20 = 0.315391565252520, c22 = 0.546274215296039;
  for (const Vec3d& d : test_directions(kSeed, 2000)) {
    const double x = d.x, y = d.y, z = d.z;
    const double want[9] = {c0,
                            c1 * y,
                            c1 * z,
                            c1 * x,
                            c2 * x * y,
                            c2 * y * z,
                            c20 * (3 * z * z - 1),
                            c2 * x * z,
                            c22 * (x * x - y * y)};
    for (int order : {3, 10}) {
      const auto got = eval(order, d);
      for (int i = 0; i < 9; ++i)
        ASSERT_NEAR(got[i], want[i], 1e-13)
            << "i = " << i << " at (" << x << ", " << y << ", " << z << ")";
    }
  }
}

TEST(SphericalHarmonics, MatchesAssociatedLegendreDefinitionForAllOrders) {
  // y_lm = sqrt(2) K_l^m P_l^m(cos theta) cos(m phi) (m > 0), sin(|m| phi) (m < 0), with the
  // C++17 std::assoc_legendre, which omits the Condon-Shortley phase as our convention does.
  double worst = 0.0;
  for (const Vec3d& d : test_directions(kSeed + 1, 500)) {
    const auto got = eval(kMaxShOrder, d);
    const double theta = std::acos(std::clamp(d.z, -1.0, 1.0));
    const double phi = std::atan2(d.y, d.x);
    for (int l = 0; l < kMaxShOrder; ++l) {
      for (int m = -l; m <= l; ++m) {
        const int am = std::abs(m);
        const double k =
            std::sqrt((2 * l + 1) / (4 * kPi) * std::tgamma(l - am + 1) / std::tgamma(l + am + 1));
        const double p = std::assoc_legendre(l, am, std::cos(theta));
        double want = k * p;
        if (m > 0) want *= std::sqrt(2.0) * std::cos(m * phi);
        if (m < 0) want *= std::sqrt(2.0) * std::sin(am * phi);
        const double scale = std::sqrt((2 * l + 1) / (4 * kPi));  // max |y_l0|
        const double err = std::abs(got[sh_index(l, m)] - want) / scale;
        worst = std::max(worst, err);
        ASSERT_LT(err, 1e-11) << "l = " << l << ", m = " << m << ": got " << got[sh_index(l, m)]
                              << ", want " << want;
      }
    }
  }
  std::printf("worst relative deviation from std::assoc_legendre: %.3g\n", worst);
}

TEST(SphericalHarmonics, AdditionTheoremAndParity) {
  // sum_m y_lm(d)^2 = (2l + 1) / (4 pi) for every direction, and y_lm(-d) = (-1)^l y_lm(d).
  for (const Vec3d& d : test_directions(kSeed + 2, 2000)) {
    const auto y = eval(kMaxShOrder, d);
    const auto yn = eval(kMaxShOrder, -d);
    for (int l = 0; l < kMaxShOrder; ++l) {
      double band = 0.0;
      for (int m = -l; m <= l; ++m) {
        band += y[sh_index(l, m)] * y[sh_index(l, m)];
        ASSERT_NEAR(yn[sh_index(l, m)], (l % 2 ? -1.0 : 1.0) * y[sh_index(l, m)], 1e-12);
      }
      const double want = (2 * l + 1) / (4 * kPi);
      ASSERT_NEAR(band, want, 1e-13 * want)
          << "band " << l << " relative error " << (band - want) / want;
    }
  }
}

TEST(SphericalHarmonics, LowerOrderIsAPrefix) {
  for (const Vec3d& d : test_directions(kSeed + 3, 100)) {
    const auto full = eval(kMaxShOrder, d);
    for (int order = 1; order < kMaxShOrder; ++order) {
      const auto part = eval(order, d);
      for (int i = 0; i < sh_count(order); ++i) ASSERT_EQ(part[i], full[i]);
    }
  }
}

TEST(SphericalHarmonics, OrthonormalUnderCubemapQuadrature) {
  const CubemapLayout layout(64);
  // Lower triangle of G = sum_k y(d_k) y(d_k)^T Omega_k. A plain loop: Eigen's product is
  // ten times slower than this in unoptimised sanitizer builds.
  std::vector<double> gram(kN * kN, 0.0);
  std::array<double, kN> y{};
  for (int k = 0; k < layout.pixel_count(); ++k) {
    sh_eval(kMaxShOrder, layout.direction(k), y);
    const double w = layout.solid_angle(k);
    for (int i = 0; i < kN; ++i) {
      const double wy = w * y[i];
      double* row = &gram[i * kN];
      for (int j = 0; j <= i; ++j) row[j] += wy * y[j];
    }
  }
  double err = 0.0;
  int worst_i = 0, worst_j = 0;
  for (int i = 0; i < kN; ++i) {
    for (int j = 0; j <= i; ++j) {
      const double e = std::abs(gram[i * kN + j] - (i == j ? 1.0 : 0.0));
      if (e > err) err = e, worst_i = i, worst_j = j;
    }
  }
  std::printf("R = 64, order 10: max |G - I| = %.3g at (%d, %d)\n", err, worst_i, worst_j);
  EXPECT_LT(err, 1e-3) << "Gram matrix of the 100 SH under cubemap quadrature, worst entry ("
                       << worst_i << ", " << worst_j << ")";
  // The constant is exact: the solid angles sum to 4 pi.
  EXPECT_NEAR(gram[0], 1.0, 1e-12);
}

TEST(SphericalHarmonics, ProjectionReproducesCoefficients) {
  std::mt19937_64 rng(kSeed + 4);
  std::normal_distribution<double> g;
  ShCoeffs want;
  want.order = kMaxShOrder;
  for (int i = 0; i < kN; ++i) want.coeffs.push_back({g(rng), g(rng), g(rng)});

  Cubemap map(64);
  for (int k = 0; k < map.layout.pixel_count(); ++k)
    map.radiance[k] = Rgb(sh_evaluate(want, map.layout.direction(k)));
  const ShCoeffs got = sh_project(map, kMaxShOrder);
  ASSERT_EQ(got.order, kMaxShOrder);
  ASSERT_EQ(got.coeffs.size(), static_cast<std::size_t>(kN));
  double err2 = 0.0, norm2 = 0.0;
  for (int i = 0; i < kN; ++i) {
    const Vec3d e = got.coeffs[i] - want.coeffs[i];
    err2 += glm::dot(e, e);
    norm2 += glm::dot(want.coeffs[i], want.coeffs[i]);
  }
  const double rel = std::sqrt(err2 / norm2);
  std::printf("order 10 round trip through a 64^2 cubemap: relative coefficient error %.3g\n", rel);
  // Bounded by |G - I| (quadrature) plus float radiance storage.
  EXPECT_LT(rel, 5e-4) << "seed " << kSeed + 4;

  // Projecting to a lower order returns the leading coefficients of the same quadrature.
  const ShCoeffs low = sh_project(map, 3);
  ASSERT_EQ(low.coeffs.size(), 9u);
  for (int i = 0; i < 9; ++i) EXPECT_LT(glm::length(low.coeffs[i] - got.coeffs[i]), 1e-12);
}

TEST(SphericalHarmonics, ProjectionOfAConstantAndOfALobe) {
  Cubemap map(32);
  for (auto& l : map.radiance) l = Rgb(2.0f, 0.0f, -1.0f);
  const ShCoeffs c = sh_project(map, 4);
  const double y00 = 0.5 / std::sqrt(kPi);
  EXPECT_NEAR(c.coeffs[0].x, 2.0 * kFourPi * y00, 1e-12);
  EXPECT_NEAR(c.coeffs[0].z, -kFourPi * y00, 1e-12);
  // Odd bands vanish by the cubemap's point symmetry; even bands only by quadrature.
  for (int i = 1; i < sh_count(4); ++i) EXPECT_NEAR(c.coeffs[i].x, 0.0, 1e-3) << "i = " << i;
  for (int i = 1; i < 4; ++i) EXPECT_NEAR(c.coeffs[i].x, 0.0, 1e-14) << "i = " << i;

  // max(0, z): c_10 = sqrt(3 / 4 pi) * (2 pi / 3) = sqrt(pi / 3); c_00 = sqrt(pi) / 2.
  Cubemap lobe(64);
  for (int k = 0; k < lobe.layout.pixel_count(); ++k)
    lobe.radiance[k] = Rgb(static_cast<float>(std::max(0.0, lobe.layout.direction(k).z)));
  const ShCoeffs cl = sh_project(lobe, 2);
  EXPECT_NEAR(cl.coeffs[0].x, std::sqrt(kPi) / 2, 1e-3);
  EXPECT_NEAR(cl.coeffs[2].y, std::sqrt(kPi / 3), 1e-3);
  EXPECT_NEAR(cl.coeffs[1].z, 0.0, 1e-6);
  EXPECT_NEAR(cl.coeffs[3].z, 0.0, 1e-6);
}

TEST(SphericalHarmonics, EvaluateSumsTheBasis) {
  std::mt19937_64 rng(kSeed + 5);
  std::normal_distribution<double> g;
  ShCoeffs c;
  c.order = 5;
  for (int i = 0; i < 25; ++i) c.coeffs.push_back({g(rng), g(rng), g(rng)});
  for (const Vec3d& d : test_directions(kSeed + 6, 200)) {
    const auto y = eval(5, d);
    Vec3d want{0.0};
    for (int i = 0; i < 25; ++i) want += c.coeffs[i] * y[i];
    EXPECT_LT(glm::length(sh_evaluate(c, d) - want), 1e-12);
  }
}

TEST(SphericalHarmonics, RejectsBadOrder) {
  Cubemap map(2);
  EXPECT_THROW(sh_project(map, 0), ParameterError);
  EXPECT_THROW(sh_project(map, kMaxShOrder + 1), ParameterError);
  ShCoeffs c;
  c.order = 11;
  c.coeffs.resize(121);
  EXPECT_THROW(sh_evaluate(c, {0, 0, 1}), ParameterError);
}

}  // namespace
}  // namespace prt
