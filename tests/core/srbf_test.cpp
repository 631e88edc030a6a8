// Spherical radial basis functions (Tsai and Shih 2006, section 4.1) and the icosphere centres:
// the closed-form spherical singular integrals (eq. 5, eq. 6 with m = 2) against numerical
// quadrature of the kernels' product over a range of bandwidths, large ones included, and against
// the Legendre series of eq. 2; the Legendre coefficients against the kernels themselves; the
// icosphere's vertex counts and spacing.
#include "prtlab/sphere/srbf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/sphere/icosphere.h"
#include "prtlab/sphere/local_frame.h"
#include "prtlab/sphere/sphere_quadrature.h"

namespace prt {
namespace {

Vec3d direction(double theta, double phi) {
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

// Legendre P_0 .. P_lmax at t.
std::vector<double> legendre(int lmax, double t) {
  std::vector<double> p(static_cast<std::size_t>(lmax) + 1);
  p[0] = 1.0;
  if (lmax >= 1) p[1] = t;
  for (int l = 1; l < lmax; ++l)
    p[static_cast<std::size_t>(l + 1)] = ((2.0 * l + 1.0) * t * p[static_cast<std::size_t>(l)] -
                                          l * p[static_cast<std::size_t>(l - 1)]) /
                                         (l + 1.0);
  return p;
}

// integral over S^2 of f(eta) by a product rule in the frame whose pole is `axis`: Gauss-Legendre
// in z on geometrically graded intervals towards z = 1 (where a kernel around `axis` with
// bandwidth up to 1 / grade^2 concentrates) times `phi_nodes` equal angles.
template <typename F>
double sphere_integral(const Vec3d& axis, F f, int phi_nodes, double finest) {
  const LocalFrame frame = LocalFrame::from_normal(axis);
  std::vector<double> edges = {1.0};
  for (double d = finest; d < 2.0; d *= 2.0) edges.push_back(1.0 - d);
  edges.push_back(-1.0);
  double sum = 0.0;
  for (std::size_t k = 0; k + 1 < edges.size(); ++k) {
    for (const auto& node : zone_gauss_rule(edges[k + 1], edges[k], 24, phi_nodes))
      sum += node.weight * f(frame.to_world(node.direction));
  }
  return sum;
}

TEST(Srbf, GaussianConvolutionEqualsQuadratureOverBandwidths) {
  // Bandwidths from a wide lobe to a very narrow one; angles scaled so the result stays well
  // above underflow (lambda theta^2 of order 1).
  const std::vector<std::pair<double, double>> pairs = {
      {0.3, 0.7}, {2, 5}, {20, 20}, {162.1, 162.1}, {300, 1000}, {5e3, 2e4}, {1e5, 1e5}};
  for (const auto& [lg, lh] : pairs) {
    for (const double scale : {0.0, 0.5, 1.5, 3.0}) {
      const double theta = scale / std::sqrt(std::min(lg, lh));
      if (theta > kPi) continue;
      const Vec3d xg = direction(0.4, 1.1);
      const LocalFrame f = LocalFrame::from_normal(xg);
      const Vec3d xh = glm::normalize(f.to_world(direction(theta, 0.7)));
      const Vec3d r = lg * xg + lh * xh;
      const Vec3d axis = glm::length(r) > 0 ? glm::normalize(r) : xg;
      const double numeric = sphere_integral(
          axis,
          [&](const Vec3d& eta) {
            return srbf_eval(SrbfKernel::kGaussian, glm::dot(eta, xg), lg) *
                   srbf_eval(SrbfKernel::kGaussian, glm::dot(eta, xh), lh);
          },
          48, 0.1 / (lg + lh));
      const double closed = srbf_convolution(SrbfKernel::kGaussian, xg, lg, xh, lh);
      ASSERT_GT(numeric, 1e-300);
      EXPECT_NEAR(closed / numeric, 1.0, 1e-6)
          << "lambda " << lg << ", " << lh << ", theta " << theta;
    }
  }
}

TEST(Srbf, GaussianConvolutionOfWideLobesEqualsAPlainSphereRule) {
  // The same without choosing the rule's pole: a plain product Gauss rule about z.
  const auto rule = zone_gauss_rule(-1.0, 1.0, 200, 400);
  for (const double lg : {0.5, 3.0, 12.7}) {
    for (const double lh : {1.0, 8.0}) {
      const Vec3d xg = direction(0.9, 0.3), xh = direction(2.0, -1.2);
      double numeric = 0;
      for (const auto& n : rule)
        numeric += n.weight * srbf_eval(SrbfKernel::kGaussian, glm::dot(n.direction, xg), lg) *
                   srbf_eval(SrbfKernel::kGaussian, glm::dot(n.direction, xh), lh);
      EXPECT_NEAR(srbf_convolution(SrbfKernel::kGaussian, xg, lg, xh, lh) / numeric, 1.0, 1e-9);
    }
  }
}

TEST(Srbf, AbelPoissonConvolutionIsFourPiTimesTheKernelOfTheProductBandwidth) {
  for (const double lg : {0.1, 0.5, 0.8}) {
    for (const double lh : {0.3, 0.7}) {
      for (const double theta : {0.0, 0.2, 1.0, 2.5}) {
        const Vec3d xg = direction(0.4, 1.1);
        const Vec3d xh =
            glm::normalize(LocalFrame::from_normal(xg).to_world(direction(theta, 0.2)));
        const auto product = [&](const Vec3d& eta) {
          return srbf_eval(SrbfKernel::kAbelPoisson, glm::dot(eta, xg), lg) *
                 srbf_eval(SrbfKernel::kAbelPoisson, glm::dot(eta, xh), lh);
        };
        // A fine rule about xg resolves both kernels: the narrowest (0.8) is ~0.2 rad wide.
        const double numeric = sphere_integral(xg, product, 720, 1e-3);
        const double closed = srbf_convolution(SrbfKernel::kAbelPoisson, xg, lg, xh, lh);
        EXPECT_NEAR(closed / numeric, 1.0, 1e-6) << lg << " " << lh << " " << theta;
        // Eq. 2 with the Legendre coefficients (2l + 1) lambda^l, an independent series.
        const auto p = legendre(400, glm::dot(xg, xh));
        double series = 0;
        for (int l = 0; l <= 400; ++l)
          series += srbf_legendre_coefficient(SrbfKernel::kAbelPoisson, l, lg) *
                    srbf_legendre_coefficient(SrbfKernel::kAbelPoisson, l, lh) * 4.0 * kPi /
                    (2.0 * l + 1.0) * p[static_cast<std::size_t>(l)];
        EXPECT_NEAR(closed / series, 1.0, 1e-10);
      }
    }
  }
}

TEST(Srbf, GaussianLegendreCoefficientsReproduceTheKernelAndEquationTwo) {
  for (const double lambda : {1e-3, 0.5, 7.0, 40.0, 162.1}) {
    const int lmax = 60 + static_cast<int>(6 * std::sqrt(lambda));
    std::vector<double> g(static_cast<std::size_t>(lmax) + 1);
    for (int l = 0; l <= lmax; ++l)
      g[static_cast<std::size_t>(l)] = srbf_legendre_coefficient(SrbfKernel::kGaussian, l, lambda);
    for (const double t : {-1.0, -0.3, 0.2, 0.9, 0.99, 1.0}) {
      const auto p = legendre(lmax, t);
      double sum = 0;
      for (int l = 0; l <= lmax; ++l)
        sum += g[static_cast<std::size_t>(l)] * p[static_cast<std::size_t>(l)];
      const double exact = srbf_eval(SrbfKernel::kGaussian, t, lambda);
      EXPECT_NEAR(sum, exact, 1e-12 + 1e-9 * exact) << "lambda " << lambda << ", t " << t;
    }
    // Eq. 2: the convolution of the kernel with itself at angle 0.3.
    const Vec3d a = direction(0.0, 0.0), b = direction(0.3, 0.0);
    const auto p = legendre(lmax, glm::dot(a, b));
    double series = 0;
    for (int l = 0; l <= lmax; ++l)
      series += g[static_cast<std::size_t>(l)] * g[static_cast<std::size_t>(l)] * 4.0 * kPi /
                (2.0 * l + 1.0) * p[static_cast<std::size_t>(l)];
    const double closed = srbf_convolution(SrbfKernel::kGaussian, a, lambda, b, lambda);
    EXPECT_NEAR(series / closed, 1.0, 1e-9) << "lambda " << lambda;
  }
}

TEST(Srbf, HugeBandwidthsNeitherOverflowNorLosePrecision) {
  const Vec3d z{0, 0, 1};
  for (const double lambda : {1e3, 1e6, 1e9, 1e12}) {
    // Same centre: 4 pi e^(-2 lambda) sinh(2 lambda) / (2 lambda) = pi (1 - e^(-4 lambda)) /
    // lambda.
    const double v = srbf_convolution(SrbfKernel::kGaussian, z, lambda, z, lambda);
    ASSERT_TRUE(std::isfinite(v));
    EXPECT_NEAR(v * lambda / kPi, 1.0, 1e-12);
  }
  // Opposite centres, equal bandwidths: r = 0, the series branch: 4 pi e^(-2 lambda).
  EXPECT_NEAR(srbf_convolution(SrbfKernel::kGaussian, z, 0.5, -z, 0.5), 4 * kPi * std::exp(-1.0),
              1e-14);
  EXPECT_EQ(srbf_convolution(SrbfKernel::kGaussian, z, 1e6, -z, 1e6), 0.0);  // underflow, not NaN
  EXPECT_TRUE(std::isfinite(srbf_legendre_coefficient(SrbfKernel::kGaussian, 3, 1e6)));
}

TEST(Srbf, BandwidthsOutOfRangeAreErrors) {
  const Vec3d z{0, 0, 1};
  EXPECT_THROW(srbf_eval(SrbfKernel::kGaussian, 0.5, 0.0), ParameterError);
  EXPECT_THROW(srbf_eval(SrbfKernel::kGaussian, 0.5, std::nan("")), ParameterError);
  EXPECT_THROW(srbf_eval(SrbfKernel::kAbelPoisson, 0.5, 1.0), ParameterError);
  EXPECT_THROW(srbf_convolution(SrbfKernel::kAbelPoisson, z, 0.5, z, -0.1), ParameterError);
  EXPECT_THROW(srbf_kernel_from("cosine"), ParameterError);
  EXPECT_EQ(srbf_kernel_from("abel_poisson"), SrbfKernel::kAbelPoisson);
  EXPECT_THROW(gaussian_bandwidth_for_sigma(0.0), ParameterError);
  EXPECT_NEAR(gaussian_bandwidth_for_sigma(kPi / 40), 1600 / (kPi * kPi), 1e-12);
}

TEST(Icosphere, CountsUnitVerticesAndSpacing) {
  const int expected[] = {12, 42, 162, 642, 2562};
  double previous = kPi;
  for (int level = 0; level <= 4; ++level) {
    const auto v = icosphere_vertices(level);
    ASSERT_EQ(static_cast<int>(v.size()), expected[level]);
    EXPECT_EQ(icosphere_level_for_count(expected[level]), level);
    Vec3d mean(0.0);
    for (const auto& p : v) {
      EXPECT_NEAR(glm::length(p), 1.0, 1e-12);
      mean += p;
    }
    EXPECT_LT(glm::length(mean) / static_cast<double>(v.size()), 1e-12);  // symmetric set
    const double d = min_geodesic_distance(v);
    EXPECT_GT(d, 0.0);
    if (level > 0) {  // each subdivision about halves the spacing
      EXPECT_LT(d, previous * 0.6);
      EXPECT_GT(d, previous * 0.4);
    }
    previous = d;
    if (level == 0) {
      EXPECT_NEAR(d, std::atan(2.0), 1e-12);  // the icosahedron's edge angle
    }
  }
  EXPECT_THROW(icosphere_level_for_count(100), ParameterError);
  EXPECT_THROW(icosphere_vertices(-1), ParameterError);
}

}  // namespace
}  // namespace prt
