// Hemisphere grid: the concentric map and its inverse, the area-preserving lift to the
// hemisphere, equal cell solid angles (measured independently of the map's formulas) and the
// cell lookup.
#include "prtlab/sphere/hemisphere_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include "prtlab/base/error.h"

namespace prt {
namespace {

constexpr std::uint64_t kSeed = 977;

// Signed solid angle of the spherical triangle (a, b, c) of unit vectors (Van Oosterom and
// Strackee 1983).
double triangle_solid_angle(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const double num = glm::dot(a, glm::cross(b, c));
  const double den = 1.0 + glm::dot(a, b) + glm::dot(b, c) + glm::dot(c, a);
  return 2.0 * std::atan2(num, den);
}

// Solid angle of the image of the square cell [a0,a1] x [b0,b1]: its boundary is walked with
// `n` points per edge, mapped to the sphere, and the resulting spherical polygon is fanned
// from the cell's centre. Only the forward map is used; the area comes from spherical
// geometry, not from the map's Jacobian.
double cell_area_by_polygon(double a0, double a1, double b0, double b1, int n) {
  std::vector<Vec2d> square;
  square.reserve(4 * n);
  for (int i = 0; i < n; ++i) square.push_back({a0 + (a1 - a0) * i / n, b0});
  for (int i = 0; i < n; ++i) square.push_back({a1, b0 + (b1 - b0) * i / n});
  for (int i = 0; i < n; ++i) square.push_back({a1 - (a1 - a0) * i / n, b1});
  for (int i = 0; i < n; ++i) square.push_back({a0, b1 - (b1 - b0) * i / n});
  const Vec3d centre = square_to_hemisphere({0.5 * (a0 + a1), 0.5 * (b0 + b1)});
  double area = 0.0;
  Vec3d prev = glm::normalize(square_to_hemisphere(square.back()));
  for (const Vec2d& ab : square) {
    const Vec3d p = glm::normalize(square_to_hemisphere(ab));
    area += triangle_solid_angle(centre, prev, p);
    prev = p;
  }
  return std::abs(area);
}

std::vector<Vec2d> special_square_points() {
  std::vector<Vec2d> pts;
  for (double a : {0.0, 0.25, 0.5, 0.75, 1.0, 1e-12, 1.0 - 1e-12, 0.5 + 1e-15, 0.5 - 1e-13})
    for (double b : {0.0, 0.25, 0.5, 0.75, 1.0, 1e-12, 1.0 - 1e-12, 0.5 + 1e-15, 0.5 - 1e-13})
      pts.push_back({a, b});
  // On and next to both diagonals, where the concentric map changes branch.
  for (double x = 0.0; x <= 1.0; x += 1.0 / 64) {
    for (double e : {0.0, 1e-14, -1e-14}) {
      pts.push_back({x, std::clamp(x + e, 0.0, 1.0)});
      pts.push_back({x, std::clamp(1.0 - x + e, 0.0, 1.0)});
    }
  }
  return pts;
}

TEST(ConcentricMap, SquareToDiskToSquareRoundTrips) {
  std::mt19937_64 rng(kSeed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec2d> pts = special_square_points();
  for (int i = 0; i < 20000; ++i) pts.push_back({u(rng), u(rng)});
  double worst = 0.0;
  for (const Vec2d& ab : pts) {
    const Vec2d p = square_to_disk_concentric(ab);
    ASSERT_LE(glm::length(p), 1.0 + 1e-15) << ab.x << ", " << ab.y;
    worst = std::max(worst, glm::length(disk_to_square_concentric(p) - ab));
  }
  EXPECT_LT(worst, 1e-14) << "seed " << kSeed;
}

TEST(ConcentricMap, DiskToSquareToDiskRoundTrips) {
  std::mt19937_64 rng(kSeed + 1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Vec2d> pts = {{0, 0}, {1, 0}, {0, 1}, {-1, 0}, {0, -1}, {1e-300, 0}, {-1e-20, 1e-20}};
  for (int i = 0; i < 16; ++i)  // region boundaries and the circle
    pts.push_back({std::cos(i * kPi / 8), std::sin(i * kPi / 8)});
  while (pts.size() < 20000) {
    const Vec2d p{u(rng), u(rng)};
    if (glm::dot(p, p) <= 1.0) pts.push_back(p);
  }
  double worst = 0.0;
  for (const Vec2d& p : pts) {
    const Vec2d ab = disk_to_square_concentric(p);
    ASSERT_GE(ab.x, -1e-15);
    ASSERT_LE(ab.x, 1.0 + 1e-15);
    ASSERT_GE(ab.y, -1e-15);
    ASSERT_LE(ab.y, 1.0 + 1e-15);
    worst = std::max(worst, glm::length(square_to_disk_concentric(ab) - p));
  }
  EXPECT_LT(worst, 1e-14) << "seed " << kSeed + 1;
}

TEST(ConcentricMap, SquareBoundaryMapsToCircleAndCentreToOrigin) {
  EXPECT_EQ(glm::length(square_to_disk_concentric({0.5, 0.5})), 0.0);
  for (int i = 0; i <= 100; ++i) {
    const double x = i / 100.0;
    for (const Vec2d& ab : {Vec2d{x, 0}, Vec2d{x, 1}, Vec2d{0, x}, Vec2d{1, x}})
      EXPECT_NEAR(glm::length(square_to_disk_concentric(ab)), 1.0, 1e-15);
  }
}

TEST(HemisphereMap, OrientationOfTheSquare) {
  // Documented in docs/conventions.md: a -> +x, b -> +y, square centre -> zenith.
  const auto near = [](const Vec3d& a, const Vec3d& b) { return glm::length(a - b) < 1e-15; };
  EXPECT_TRUE(near(square_to_hemisphere({0.5, 0.5}), {0, 0, 1}));
  EXPECT_TRUE(near(square_to_hemisphere({1.0, 0.5}), {1, 0, 0}));
  EXPECT_TRUE(near(square_to_hemisphere({0.5, 1.0}), {0, 1, 0}));
  EXPECT_TRUE(near(square_to_hemisphere({0.0, 0.5}), {-1, 0, 0}));
  EXPECT_TRUE(near(square_to_hemisphere({0.5, 0.0}), {0, -1, 0}));
  const double h = std::sqrt(0.5);
  EXPECT_TRUE(near(square_to_hemisphere({1.0, 1.0}), {h, h, 0}));
}

TEST(HemisphereMap, RoundTripsAndStaysOnTheUpperHemisphere) {
  std::mt19937_64 rng(kSeed + 2);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec2d> pts = special_square_points();
  for (int i = 0; i < 20000; ++i) pts.push_back({u(rng), u(rng)});
  double worst = 0.0;
  for (const Vec2d& ab : pts) {
    const Vec3d d = square_to_hemisphere(ab);
    ASSERT_NEAR(glm::length(d), 1.0, 1e-15);
    ASSERT_GE(d.z, 0.0);
    worst = std::max(worst, glm::length(hemisphere_to_square(d) - ab));
  }
  // The inverse divides xy by sqrt(1 + z) instead of taking sqrt(1 - z), so it stays well
  // conditioned at the pole and at the horizon alike.
  EXPECT_LT(worst, 1e-14);
  double worst_dir = 0.0;
  std::normal_distribution<double> g;
  for (int i = 0; i < 20000; ++i) {
    Vec3d d = glm::normalize(Vec3d{g(rng), g(rng), g(rng)});
    d.z = std::abs(d.z);
    worst_dir = std::max(worst_dir, glm::length(square_to_hemisphere(hemisphere_to_square(d)) - d));
    // Below the horizon: mirrored.
    const Vec3d m{d.x, d.y, -d.z};
    ASSERT_LT(glm::length(hemisphere_to_square(m) - hemisphere_to_square(d)), 1e-15);
  }
  EXPECT_LT(worst_dir, 1e-14) << "seed " << kSeed + 2;
}

TEST(HemisphereMap, AreaElementIsConstant) {
  // |d/da x d/db| = 2 pi everywhere off the diagonals (the square's unit area covers 2 pi sr),
  // by central differences.
  std::mt19937_64 rng(kSeed + 3);
  std::uniform_real_distribution<double> u(0.01, 0.99);
  const double h = 1e-6;
  double worst = 0.0;
  int used = 0;
  while (used < 2000) {
    const Vec2d ab{u(rng), u(rng)};
    const double du = ab.x - 0.5, dv = ab.y - 0.5;
    if (std::abs(std::abs(du) - std::abs(dv)) < 4 * h) continue;  // a kink inside the stencil
    const Vec3d da =
        (square_to_hemisphere(ab + Vec2d{h, 0}) - square_to_hemisphere(ab - Vec2d{h, 0})) / (2 * h);
    const Vec3d db =
        (square_to_hemisphere(ab + Vec2d{0, h}) - square_to_hemisphere(ab - Vec2d{0, h})) / (2 * h);
    worst = std::max(worst, std::abs(glm::length(glm::cross(da, db)) / kTwoPi - 1.0));
    ++used;
  }
  EXPECT_LT(worst, 1e-6) << "worst relative deviation of the area element";
}

class HemisphereGridSide : public ::testing::TestWithParam<int> {};

TEST_P(HemisphereGridSide, EveryCellHasSolidAngleTwoPiOverM) {
  const int s = GetParam();
  const HemisphereGrid grid(s);
  ASSERT_EQ(grid.cell_count(), s * s);
  const double want = kTwoPi / (s * s);
  EXPECT_DOUBLE_EQ(grid.cell_solid_angle(), want);
  double worst = 0.0, total = 0.0;
  for (int row = 0; row < s; ++row) {
    for (int col = 0; col < s; ++col) {
      const double area = cell_area_by_polygon(double(col) / s, double(col + 1) / s,
                                               double(row) / s, double(row + 1) / s, 1500);
      total += area;
      worst = std::max(worst, std::abs(area - want));
      EXPECT_NEAR(area, want, 1e-6)
          << "cell (" << col << ", " << row << ") relative error " << (area - want) / want;
    }
  }
  EXPECT_NEAR(total, kTwoPi, 1e-6);
  std::printf("S = %d: worst |cell solid angle - 2 pi / S^2| = %.3g sr (relative %.3g)\n", s, worst,
              worst / want);
}

TEST_P(HemisphereGridSide, CellOfCentreIsTheCellAndCentresFollowTheIndex) {
  const int s = GetParam();
  const HemisphereGrid grid(s);
  for (int row = 0; row < s; ++row) {
    for (int col = 0; col < s; ++col) {
      const int j = row * s + col;
      const Vec3d want = square_to_hemisphere({(col + 0.5) / s, (row + 0.5) / s});
      EXPECT_LT(glm::length(grid.direction(j) - want), 1e-15);
      EXPECT_GT(grid.direction(j).z, 0.0);
      EXPECT_EQ(grid.cell_of(grid.direction(j)), j);
      EXPECT_EQ(grid.cell_of(3.0 * grid.direction(j)), j);
    }
  }
}

TEST_P(HemisphereGridSide, CellOfInvertsTheForwardMap) {
  // A point drawn in square cell (col, row) and mapped to the sphere is found in that cell.
  const int s = GetParam();
  const HemisphereGrid grid(s);
  std::mt19937_64 rng(kSeed + 10 + s);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 20000; ++i) {
    const Vec2d ab{u(rng), u(rng)};
    const double fa = ab.x * s, fb = ab.y * s;
    // Skip points within rounding of a cell edge, where either answer is right.
    if (std::abs(fa - std::round(fa)) < 1e-9 || std::abs(fb - std::round(fb)) < 1e-9) continue;
    const int want = static_cast<int>(fb) * s + static_cast<int>(fa);
    const Vec3d d = square_to_hemisphere(ab);
    if (d.z <= 0.0) continue;
    ASSERT_EQ(grid.cell_of(d), want)
        << "a = " << ab.x << ", b = " << ab.y << ", seed " << kSeed + 10 + s;
  }
}

INSTANTIATE_TEST_SUITE_P(Sides, HemisphereGridSide, ::testing::Values(1, 5, 8, 12));

TEST(HemisphereGrid, BelowHorizonIsMinusOneAndHorizonIsClamped) {
  const HemisphereGrid grid(8);
  EXPECT_EQ(grid.cell_of({0, 0, -1}), -1);
  EXPECT_EQ(grid.cell_of({0.3, -0.2, -0.1}), -1);
  EXPECT_EQ(grid.cell_of({1, 0, 0}), -1);
  EXPECT_EQ(grid.cell_of({0, 0, 0}), -1);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(grid.cell_of({nan, 0, 1}), -1);
  EXPECT_EQ(grid.cell_of({0, 0, nan}), -1);
  // Just above the horizon in every direction: a valid edge cell of the square.
  for (int i = 0; i < 360; ++i) {
    const double phi = i * kPi / 180;
    const int j = grid.cell_of({std::cos(phi), std::sin(phi), 1e-300});
    ASSERT_GE(j, 0);
    ASSERT_LT(j, grid.cell_count());
    const int col = j % 8, row = j / 8;
    EXPECT_TRUE(col == 0 || col == 7 || row == 0 || row == 7) << "phi " << phi;
  }
  EXPECT_EQ(grid.cell_of({0, 0, 1}), grid.cell_of({1e-12, 1e-12, 1}));
}

TEST(HemisphereGrid, RejectsBadSide) {
  EXPECT_THROW(HemisphereGrid(0), ParameterError);
  EXPECT_THROW(HemisphereGrid(-1), ParameterError);
}

// The closed-form projected solid angles agree with a brute-force midpoint quadrature of
// cos(theta) through the map (an independent computation), and sum to pi.
TEST(HemisphereGrid, ProjectedSolidAnglesMatchQuadratureAndSumToPi) {
  for (int side : {1, 3, 8, 12}) {
    const HemisphereGrid grid(side);
    const std::vector<double> p = grid.projected_solid_angles();
    ASSERT_EQ(p.size(), static_cast<std::size_t>(side * side));
    double sum = 0.0;
    constexpr int kSub = 200;
    for (int j = 0; j < side * side; ++j) {
      const int row = j / side, col = j % side;
      double q = 0.0;
      for (int sy = 0; sy < kSub; ++sy)
        for (int sx = 0; sx < kSub; ++sx)
          q += square_to_hemisphere(
                   {(col + (sx + 0.5) / kSub) / side, (row + (sy + 0.5) / kSub) / side})
                   .z;
      q *= grid.cell_solid_angle() / (kSub * kSub);
      EXPECT_NEAR(p[j], q, 1e-4 * grid.cell_solid_angle()) << "side " << side << " cell " << j;
      EXPECT_GT(p[j], 0.0);
      EXPECT_LT(p[j], grid.cell_solid_angle());
      sum += p[j];
    }
    EXPECT_NEAR(sum, kPi, 1e-12) << "side " << side;
  }
}

}  // namespace
}  // namespace prt
