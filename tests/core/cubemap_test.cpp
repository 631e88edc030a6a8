// Cubemap layout: exact solid angles, the documented face order and orientation, pixel lookup
// (including face edges and corners) and the light vector.
#include "prtlab/sphere/cubemap.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "prtlab/base/error.h"
#include "support/random_directions.h"

namespace prt {
namespace {

constexpr std::uint64_t kSeed = 20240601;

using testing::random_direction;

double angle_between(const Vec3d& a, const Vec3d& b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

// The face table of cubemap.h, typed again here so that a change in either is caught.
Vec3d documented_direction(int face, double s, double t) {
  const Vec3d table[6] = {{1, -t, -s}, {-1, -t, s}, {s, 1, t},
                          {s, -1, -t}, {s, -t, 1},  {-s, -t, -1}};
  return glm::normalize(table[face]);
}

class CubemapResolution : public ::testing::TestWithParam<int> {};

TEST_P(CubemapResolution, SolidAnglesArePositiveAndSumToFourPi) {
  const CubemapLayout layout(GetParam());
  ASSERT_EQ(layout.pixel_count(), 6 * GetParam() * GetParam());
  double sum = 0.0;
  for (int k = 0; k < layout.pixel_count(); ++k) {
    ASSERT_GT(layout.solid_angle(k), 0.0) << "pixel " << k;
    sum += layout.solid_angle(k);
  }
  EXPECT_NEAR(sum, kFourPi, 1e-6) << "relative error " << (sum - kFourPi) / kFourPi;
}

TEST_P(CubemapResolution, PixelOfCentreDirectionIsThePixel) {
  const CubemapLayout layout(GetParam());
  for (int k = 0; k < layout.pixel_count(); ++k) {
    ASSERT_EQ(layout.pixel_of(layout.direction(k)), k);
    // Scale must not matter.
    ASSERT_EQ(layout.pixel_of(37.5 * layout.direction(k)), k);
  }
}

INSTANTIATE_TEST_SUITE_P(Resolutions, CubemapResolution, ::testing::Values(1, 2, 7, 8, 32, 64));

TEST(Cubemap, SingleTexelFacesEachCoverASixthOfTheSphere) {
  const CubemapLayout layout(1);
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(layout.solid_angle(k), kFourPi / 6.0, 1e-14);
}

TEST(Cubemap, SolidAngleApproachesCentreApproximation) {
  // Centre approximation: (2/R)^2 / (1 + s^2 + t^2)^{3/2}. Its relative error is O(1/R^2), so
  // the worst error must fall by about 4 when R doubles.
  auto worst = [](int r) {
    const CubemapLayout layout(r);
    double w = 0.0;
    for (int y = 0; y < r; ++y) {
      for (int x = 0; x < r; ++x) {
        const double s = (2.0 * x + 1.0) / r - 1.0, t = (2.0 * y + 1.0) / r - 1.0;
        const double approx = (4.0 / (r * r)) / std::pow(1.0 + s * s + t * t, 1.5);
        const double exact = layout.solid_angle(layout.index(0, x, y));
        w = std::max(w, std::abs(exact - approx) / exact);
      }
    }
    return w;
  };
  const double e32 = worst(32), e64 = worst(64);
  EXPECT_LT(e64, 3e-4) << "worst relative error of the centre approximation at R=64";
  EXPECT_GT(e32 / e64, 3.5) << "e32 " << e32 << " e64 " << e64;
  EXPECT_LT(e32 / e64, 4.5) << "e32 " << e32 << " e64 " << e64;
}

TEST(Cubemap, FaceOrderAndOrientationMatchTheDocumentedTable) {
  const int r = 5;
  const CubemapLayout layout(r);
  for (int face = 0; face < 6; ++face) {
    for (int y = 0; y < r; ++y) {
      for (int x = 0; x < r; ++x) {
        const int k = layout.index(face, x, y);
        EXPECT_EQ(k, face * r * r + y * r + x);
        const double s = 2.0 * (x + 0.5) / r - 1.0, t = 2.0 * (y + 0.5) / r - 1.0;
        const Vec3d want = documented_direction(face, s, t);
        EXPECT_LT(glm::length(layout.direction(k) - want), 1e-15) << "face " << face;
      }
    }
  }
  // Face f looks down its axis: +X, -X, +Y, -Y, +Z, -Z.
  const Vec3d axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int face = 0; face < 6; ++face)
    EXPECT_LT(glm::length(CubemapLayout::face_direction(face, 0, 0) - axes[face]), 1e-15);
}

TEST(Cubemap, AllSixFacesAreTheSamePixelSet) {
  const int r = 16;
  const CubemapLayout layout(r);
  // Every face holds the same multiset of solid angles, with the square's 8 symmetries.
  std::vector<double> face0(layout.solid_angles().begin(), layout.solid_angles().begin() + r * r);
  for (int face = 1; face < 6; ++face) {
    for (int i = 0; i < r * r; ++i)
      EXPECT_DOUBLE_EQ(layout.solid_angle(face * r * r + i), face0[i]) << "face " << face;
  }
  for (int y = 0; y < r; ++y) {
    for (int x = 0; x < r; ++x) {
      const double w = face0[y * r + x];
      EXPECT_NEAR(face0[y * r + (r - 1 - x)], w, 1e-16);
      EXPECT_NEAR(face0[(r - 1 - y) * r + x], w, 1e-16);
      EXPECT_NEAR(face0[x * r + y], w, 1e-16);
    }
  }
  // The direction set is closed under the point reflection and under the cyclic
  // permutation of axes, pixel for pixel with equal solid angles: this ties the six face
  // orientations together, not just the six tables.
  for (int k = 0; k < layout.pixel_count(); ++k) {
    const Vec3d d = layout.direction(k);
    for (const Vec3d& image : {-d, Vec3d{d.y, d.z, d.x}, Vec3d{d.z, d.x, d.y}}) {
      const int j = layout.pixel_of(image);
      ASSERT_LT(glm::length(layout.direction(j) - image), 1e-14) << "pixel " << k;
      ASSERT_NEAR(layout.solid_angle(j), layout.solid_angle(k), 1e-16) << "pixel " << k;
    }
  }
}

TEST(Cubemap, RandomDirectionsLandInTheirPixel) {
  const int r = 32;
  const CubemapLayout layout(r);
  std::mt19937_64 rng(kSeed);
  const double pixel_angle = 2.0 / r;  // angular width of a pixel at a face centre
  // Brute-force nearest centre on plain arrays (glm is slow in unoptimised test builds).
  std::vector<double> cx, cy, cz;
  for (const Vec3d& c : layout.directions())
    cx.push_back(c.x), cy.push_back(c.y), cz.push_back(c.z);
  const auto nearest = [&](const Vec3d& d) {
    int best = 0;
    double best_dot = -2.0;
    for (std::size_t j = 0; j < cx.size(); ++j) {
      const double dj = cx[j] * d.x + cy[j] * d.y + cz[j] * d.z;
      if (dj > best_dot) best_dot = dj, best = static_cast<int>(j);
    }
    return best;
  };
  int nearest_mismatch = 0;
  double worst_excess = 0.0;
  const int samples = 2000;
  for (int i = 0; i < samples; ++i) {
    const Vec3d d = random_direction(rng);
    const int k = layout.pixel_of(d);
    ASSERT_GE(k, 0);
    ASSERT_LT(k, layout.pixel_count());

    // Containment: the pixel's edges are great circles through its corner directions, so d
    // is inside when it is on the centre's side of all four.
    const int face = k / (r * r), x = k % r, y = (k / r) % r;
    const double s0 = 2.0 * x / r - 1, s1 = 2.0 * (x + 1) / r - 1;
    const double t0 = 2.0 * y / r - 1, t1 = 2.0 * (y + 1) / r - 1;
    const Vec3d c[4] = {documented_direction(face, s0, t0), documented_direction(face, s1, t0),
                        documented_direction(face, s1, t1), documented_direction(face, s0, t1)};
    for (int e = 0; e < 4; ++e) {
      const Vec3d normal = glm::cross(c[e], c[(e + 1) % 4]);
      const double side_d = glm::dot(normal, d);
      const double side_centre = glm::dot(normal, layout.direction(k));
      ASSERT_GT(side_centre * side_d, -1e-15) << "direction outside pixel " << k << " edge " << e;
    }

    // Nearest centre over the whole sphere. Gnomonic pixels are parallelograms whose skew
    // grows away from the face centre (120 degree corners at the cube's corners), so a point
    // in a pixel's acute corner can be nearer a diagonal neighbour's centre: measured 5 % of
    // random points at R = 32, by at most 0.16 of a pixel width.
    const int best = nearest(d);
    if (best != k) {
      ++nearest_mismatch;
      const double excess =
          angle_between(d, layout.direction(k)) - angle_between(d, layout.direction(best));
      worst_excess = std::max(worst_excess, excess / pixel_angle);
    }
  }
  RecordProperty("nearest_mismatch", nearest_mismatch);
  EXPECT_LT(nearest_mismatch, samples * 8 / 100) << "seed " << kSeed;
  EXPECT_LT(worst_excess, 0.25)
      << "own centre farther than the nearest by this fraction of a pixel";
  std::printf("nearest-centre mismatches %d / %d, worst excess %.4g pixel\n", nearest_mismatch,
              samples, worst_excess);
}

TEST(Cubemap, FaceCoordsAndFaceDirectionRoundTrip) {
  std::mt19937_64 rng(kSeed + 1);
  for (int i = 0; i < 10000; ++i) {
    const Vec3d d = random_direction(rng);
    int face = -1;
    double s = 9, t = 9;
    CubemapLayout::face_coords(2.5 * d, face, s, t);
    ASSERT_GE(face, 0);
    ASSERT_LT(face, 6);
    ASSERT_LE(std::abs(s), 1.0);
    ASSERT_LE(std::abs(t), 1.0);
    ASSERT_LT(glm::length(CubemapLayout::face_direction(face, s, t) - d), 1e-14);
  }
  std::uniform_real_distribution<double> u(-0.999, 0.999);
  for (int i = 0; i < 10000; ++i) {
    const int face = i % 6;
    const double s = u(rng), t = u(rng);
    int f2 = -1;
    double s2 = 9, t2 = 9;
    CubemapLayout::face_coords(CubemapLayout::face_direction(face, s, t), f2, s2, t2);
    ASSERT_EQ(f2, face);
    ASSERT_NEAR(s2, s, 1e-14);
    ASSERT_NEAR(t2, t, 1e-14);
  }
}

TEST(Cubemap, PixelOfIsRobustAtFaceEdgesAndCorners) {
  const int r = 8;
  const CubemapLayout layout(r);
  // Half the angular diagonal of the largest pixel, plus slack: the pixel returned for a
  // point on an edge or corner must be one of the pixels touching it.
  const double reach = std::sqrt(2.0) * (2.0 / r);
  std::vector<Vec3d> probes;
  for (int a = -1; a <= 1; ++a)
    for (int b = -1; b <= 1; ++b)
      for (int c = -1; c <= 1; ++c)
        if (a || b || c) probes.push_back({double(a), double(b), double(c)});
  // Points exactly on face edges, and a hair to either side.
  for (int face = 0; face < 6; ++face) {
    for (double v : {-1.0, -0.3, 0.0, 0.55, 1.0}) {
      for (double eps : {0.0, 1e-17, -1e-17, 1e-12, -1e-12}) {
        probes.push_back(CubemapLayout::face_direction(face, 1.0 + eps, v));
        probes.push_back(CubemapLayout::face_direction(face, v, -1.0 - eps));
      }
    }
  }
  probes.push_back({1e-300, 0, 0});
  probes.push_back({0, -1e300, 1e300});
  for (const Vec3d& p : probes) {
    const int k = layout.pixel_of(p);
    ASSERT_GE(k, 0);
    ASSERT_LT(k, layout.pixel_count());
    const Vec3d scaled = p / std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    EXPECT_LT(angle_between(layout.direction(k), glm::normalize(scaled)), reach)
        << "probe (" << p.x << ", " << p.y << ", " << p.z << ")";
  }
}

TEST(Cubemap, TotalPowerAndLightVector) {
  Cubemap map(16);
  for (auto& l : map.radiance) l = Rgb(1.0f, 2.0f, 0.5f);
  const Vec3d p = map.total_power();
  EXPECT_NEAR(p.x, kFourPi, 1e-9);
  EXPECT_NEAR(p.y, 2 * kFourPi, 1e-9);
  EXPECT_NEAR(p.z, 0.5 * kFourPi, 1e-9);

  // A clamped cosine lobe integrates to pi; midpoint quadrature on exact areas is O(1/R^2).
  Cubemap lobe(64);
  for (int k = 0; k < lobe.layout.pixel_count(); ++k) {
    const float c = static_cast<float>(std::max(0.0, lobe.layout.direction(k).z));
    lobe.radiance[k] = Rgb(c, 2 * c, 0);
  }
  const Vec3d lp = lobe.total_power();
  EXPECT_NEAR(lp.x, kPi, 1e-3 * kPi) << "relative error " << (lp.x - kPi) / kPi;
  EXPECT_NEAR(lp.y, 2 * kPi, 2e-3 * kPi);
  EXPECT_EQ(lp.z, 0.0);

  const std::vector<Rgb> l = lobe.light_vector();
  ASSERT_EQ(l.size(), lobe.radiance.size());
  Vec3d sum{0.0};
  for (std::size_t k = 0; k < l.size(); ++k) {
    ASSERT_FLOAT_EQ(l[k].x, static_cast<float>(lobe.radiance[k].x * lobe.layout.solid_angle(k)));
    sum += Vec3d(l[k]);
  }
  EXPECT_NEAR(sum.x, lp.x, 1e-5 * lp.x);
  EXPECT_NEAR(sum.y, lp.y, 1e-5 * lp.y);
}

TEST(Cubemap, RejectsBadResolution) {
  EXPECT_THROW(CubemapLayout(0), ParameterError);
  EXPECT_THROW(CubemapLayout(-3), ParameterError);
}

}  // namespace
}  // namespace prt
