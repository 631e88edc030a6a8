// BTF lookup: the float concentric map, view interpolation on the sphere (exact at sample
// centres, continuous across cells, clamped at the horizon), texel wrap-around, and eval/shade
// as weighted sums of the stored samples.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "prtlab/btf/btf.h"
#include "prtlab/base/error.h"
#include "prtlab/sphere/hemisphere_grid.h"

namespace prt {
namespace {

// Dense weight vector over all V views (duplicate indices summed).
std::vector<double> dense_weights(int side, Vec3 e) {
  const BtfViewSamples s = btf_view_samples(side, e);
  std::vector<double> w(static_cast<std::size_t>(side) * side, 0.0);
  for (int k = 0; k < 4; ++k) w[s.view[k]] += s.weight[k];
  return w;
}

double l1_distance(const std::vector<double>& a, const std::vector<double>& b) {
  double d = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) d += std::abs(a[i] - b[i]);
  return d;
}

TEST(BtfLookup, FloatConcentricMapMatchesDouble) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  double worst_fwd = 0.0, worst_inv = 0.0;
  for (int i = 0; i < 20000; ++i) {
    const Vec2d ab(u01(rng), u01(rng));
    const Vec3d d = square_to_hemisphere(ab);
    const Vec3 df = square_to_hemisphere_f(Vec2(ab));
    worst_fwd = std::max(worst_fwd, glm::length(Vec3d(df) - d));
    const Vec2 abf = hemisphere_to_square_f(Vec3(d));
    worst_inv = std::max(worst_inv, glm::length(Vec2d(abf) - hemisphere_to_square(d)));
  }
  EXPECT_LT(worst_fwd, 2e-6);
  EXPECT_LT(worst_inv, 2e-6);
}

TEST(BtfLookup, ExactAtSampleCentres) {
  for (const int side : {1, 2, 4, 12}) {
    const HemisphereGrid grid(side);
    for (int j = 0; j < grid.cell_count(); ++j) {
      const auto w = dense_weights(side, Vec3(grid.direction(j)));
      EXPECT_NEAR(w[j], 1.0, 2e-5) << "side " << side << " view " << j;
    }
  }
}

TEST(BtfLookup, WeightsArePartitionOfUnity) {
  std::mt19937 rng(11);
  std::normal_distribution<float> g;
  for (int i = 0; i < 20000; ++i) {
    const Vec3 e(g(rng), g(rng), g(rng));  // includes directions below the horizon
    const BtfViewSamples s = btf_view_samples(12, e);
    float sum = 0.0f;
    for (int k = 0; k < 4; ++k) {
      EXPECT_GE(s.weight[k], 0.0f);
      EXPECT_GE(s.view[k], 0);
      EXPECT_LT(s.view[k], 144);
      sum += s.weight[k];
    }
    EXPECT_NEAR(sum, 1.0f, 1e-6f);
  }
}

// Walk fine paths over the hemisphere, crossing many cell boundaries, the square's diagonals
// (where the concentric map has a kink), the pole and the outer ring of cells: consecutive
// weight vectors must differ by about the step times the weights' slope, never by a jump. A
// discontinuous scheme (nearest sample, or weights that do not vanish on the far samples at a
// cell boundary) jumps by 0.1 .. 2 here.
TEST(BtfLookup, ContinuousAcrossCellBoundaries) {
  constexpr int kSide = 12;
  constexpr int kSteps = 40000;
  struct Path {
    double phi;          // azimuth of the great half-circle through the zenith
    double theta_limit;  // runs from -limit to +limit in polar angle
  };
  const Path paths[] = {{0.0, 1.5}, {0.3, 1.55}, {kPi / 4, 1.55}, {1.1, 1.5}, {2.0, 1.57}};
  double worst = 0.0;
  for (const Path& p : paths) {
    std::vector<double> prev;
    for (int i = 0; i <= kSteps; ++i) {
      const double th = -p.theta_limit + 2.0 * p.theta_limit * i / kSteps;
      const Vec3 e(static_cast<float>(std::sin(th) * std::cos(p.phi)),
                   static_cast<float>(std::sin(th) * std::sin(p.phi)),
                   static_cast<float>(std::cos(th)));
      auto w = dense_weights(kSide, e);
      if (!prev.empty()) worst = std::max(worst, l1_distance(w, prev));
      prev = std::move(w);
    }
  }
  // Around the horizon, in the outer ring of cells.
  {
    std::vector<double> prev;
    for (int i = 0; i <= kSteps; ++i) {
      const double phi = kTwoPi * i / kSteps, th = 1.45;
      const Vec3 e(static_cast<float>(std::sin(th) * std::cos(phi)),
                   static_cast<float>(std::sin(th) * std::sin(phi)),
                   static_cast<float>(std::cos(th)));
      auto w = dense_weights(kSide, e);
      if (!prev.empty()) worst = std::max(worst, l1_distance(w, prev));
      prev = std::move(w);
    }
  }
  // Step about 7.5e-5 rad, sample spacing about 0.13 rad: the slope bound gives ~2e-3.
  EXPECT_LT(worst, 5e-3);
}

// The weights are measured on the sphere: halfway (in angle) between two samples of a row the
// two get equal weight, which bilinear interpolation in the square does not give where the
// concentric map stretches the row non-uniformly.
TEST(BtfLookup, EqualAngularDistanceGivesEqualWeights) {
  constexpr int kSide = 12;
  const HemisphereGrid grid(kSide);
  for (const int row : {0, 3, 6, 10}) {
    for (int col = 0; col + 1 < kSide; ++col) {
      const Vec3d a = grid.direction(row * kSide + col), b = grid.direction(row * kSide + col + 1);
      // The point on the row's curve (constant b) equidistant from both samples.
      const double bcoord = (row + 0.5) / kSide;
      double lo = (col + 0.5) / kSide, hi = (col + 1.5) / kSide;
      for (int it = 0; it < 60; ++it) {
        const double mid = 0.5 * (lo + hi);
        const Vec3d m = square_to_hemisphere({mid, bcoord});
        (glm::length(m - a) < glm::length(m - b) ? lo : hi) = mid;
      }
      const auto w = dense_weights(kSide, Vec3(square_to_hemisphere({lo, bcoord})));
      EXPECT_NEAR(w[row * kSide + col], 0.5, 2e-4) << "row " << row << " col " << col;
      EXPECT_NEAR(w[row * kSide + col + 1], 0.5, 2e-4) << "row " << row << " col " << col;
    }
  }
}

TEST(BtfLookup, BelowTheHorizonClampsToIt) {
  const Vec3 below(0.6f, -0.3f, -0.4f);
  const Vec3 horizon = glm::normalize(Vec3(0.6f, -0.3f, 0.0f));
  EXPECT_LT(glm::length(clamp_to_hemisphere(below) - horizon), 1e-6f);
  const auto a = dense_weights(12, below), b = dense_weights(12, horizon);
  EXPECT_LT(l1_distance(a, b), 1e-6);
  // Only the outermost ring of samples contributes on the horizon.
  for (int j = 0; j < 144; ++j) {
    const int row = j / 12, col = j % 12;
    const bool outer = row == 0 || row == 11 || col == 0 || col == 11;
    if (!outer) {
      EXPECT_EQ(a[j], 0.0) << j;
    }
  }
  EXPECT_EQ(clamp_to_hemisphere(Vec3(0.f, 0.f, -1.f)), Vec3(1.f, 0.f, 0.f));
  EXPECT_EQ(clamp_to_hemisphere(Vec3(0.f, 0.f, 0.f)), Vec3(0.f, 0.f, 1.f));
  EXPECT_EQ(clamp_to_hemisphere(Vec3(NAN, 0.f, 1.f)), Vec3(0.f, 0.f, 1.f));
}

// A synthetic BTF whose value encodes (texel, view, light), to check indexing and the sums.
Btf coded_btf(int u, int vs, int ls) {
  const int v = vs * vs, m = ls * ls;
  std::vector<float> rgb(static_cast<std::size_t>(u) * u * v * m * 3);
  for (int t = 0; t < u * u; ++t)
    for (int k = 0; k < v; ++k)
      for (int j = 0; j < m; ++j)
        for (int c = 0; c < 3; ++c)
          rgb[((static_cast<std::size_t>(t) * v + k) * m + j) * 3 + c] =
              static_cast<float>(t * 10000 + k * 100 + j) + 0.25f * c;
  return Btf("coded", u, vs, ls, std::move(rgb));
}

TEST(BtfLookup, LayoutAndNearestTexelWrap) {
  const Btf b = coded_btf(4, 3, 2);
  EXPECT_EQ(b.value(5, 7, 3), Rgb(50703.0f, 50703.25f, 50703.5f));
  EXPECT_EQ(b.texel_at({0.1f, 0.6f}), 2 * 4 + 0);
  EXPECT_EQ(b.texel_at({1.1f, -0.4f}), 2 * 4 + 0);  // wraps in both directions
  EXPECT_EQ(b.texel_at({0.999999f, 0.0f}), 3);
  EXPECT_EQ(b.texel_at({-1e-7f, 0.0f}), 3);
  EXPECT_EQ(b.texel_at({INFINITY, NAN}), 0);  // defined, if meaningless
  EXPECT_FALSE(b.view_independent());
}

TEST(BtfLookup, BilinearTexelsWrapAtTheEdge) {
  const Btf b = coded_btf(4, 1, 1);
  const BtfTexelSamples s = b.texel_samples({0.0f, 0.125f}, TexelFilter::kBilinear);
  ASSERT_EQ(s.count, 4);
  // u = 0 is halfway between the centres of texel 3 (wrapped) and texel 0; v = 1/8 is row 0's
  // centre.
  std::vector<double> w(16, 0.0);
  for (int k = 0; k < 4; ++k) w[s.texel[k]] += s.weight[k];
  EXPECT_NEAR(w[0], 0.5, 1e-6);
  EXPECT_NEAR(w[3], 0.5, 1e-6);
}

TEST(BtfLookup, EvalAndShadeAreWeightedSums) {
  const Btf b = coded_btf(4, 4, 2);
  const HemisphereGrid views(4);
  const Vec2 uv(0.3f, 0.8f);
  const int t = b.texel_at(uv);
  // At a sample centre eval returns the stored sample.
  for (int k = 0; k < 16; ++k) {
    const Rgb got = b.eval(uv, Vec3(views.direction(k)), 2);
    EXPECT_NEAR(got.x, b.value(t, k, 2).x, 2e-5 * got.x) << k;
  }
  const Vec3 e = glm::normalize(Vec3(0.3f, -0.5f, 0.6f));
  const BtfViewSamples vs = btf_view_samples(4, e);
  std::vector<Rgb> lights(4);
  b.eval_lights(uv, e, lights);
  std::vector<Rgb> radiance = {
      {1.f, 0.f, 2.f}, {0.5f, 0.5f, 0.5f}, {0.f, 3.f, 0.f}, {1.f, 1.f, 1.f}};
  Rgb expected_shade(0.0f);
  for (int j = 0; j < 4; ++j) {
    Rgb expected(0.0f);
    for (int k = 0; k < 4; ++k) expected += vs.weight[k] * b.value(t, vs.view[k], j);
    EXPECT_LT(glm::length(lights[j] - expected), 1e-6f * glm::length(expected));
    EXPECT_LT(glm::length(b.eval(uv, e, j) - expected), 1e-6f * glm::length(expected));
    expected_shade += expected * radiance[j];
  }
  const Rgb shaded = b.shade(uv, e, radiance);
  EXPECT_LT(glm::length(shaded - expected_shade), 1e-6f * glm::length(expected_shade));
}

TEST(BtfLookup, ConstructorChecksTheSize) {
  EXPECT_THROW(Btf("x", 2, 2, 2, std::vector<float>(2 * 2 * 4 * 4 * 3 - 1)), ParameterError);
  EXPECT_THROW(Btf("x", 0, 2, 2, {}), ParameterError);
  const Btf flat("x", 2, 2, 2, std::vector<float>(2 * 2 * 4 * 4 * 3, 0.5f));
  EXPECT_TRUE(flat.view_independent());
}

}  // namespace
}  // namespace prt
