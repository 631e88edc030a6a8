// Visibility: the supersampled direction table, Embree occlusion, and the per-point visibility
// cubemap against analytic answers (an open plane, a sphere's cone of shadow).
#include "prtlab/transfer/visibility.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "prtlab/sphere/cubemap.h"
#include "prtlab/base/error.h"
#include "prtlab/geometry/procedural_shapes.h"

namespace prt {
namespace {

double angle_between(const Vec3d& a, const Vec3d& b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

void translate(Mesh& mesh, const Vec3d& offset) {
  for (auto& p : mesh.positions) p += Vec3(offset);
}

// Pixel k's corners on the sphere.
std::array<Vec3d, 4> pixel_corners(const CubemapLayout& layout, int k) {
  const int r = layout.resolution();
  const int face = k / (r * r), x = (k % (r * r)) % r, y = (k % (r * r)) / r;
  auto c = [&](int i) { return 2.0 * i / r - 1.0; };
  return {CubemapLayout::face_direction(face, c(x), c(y)),
          CubemapLayout::face_direction(face, c(x + 1), c(y)),
          CubemapLayout::face_direction(face, c(x + 1), c(y + 1)),
          CubemapLayout::face_direction(face, c(x), c(y + 1))};
}

class SupersampledTable : public ::testing::TestWithParam<std::pair<int, int>> {};

TEST_P(SupersampledTable, SubpixelsTileTheirPixels) {
  const auto [r, s] = GetParam();
  const SupersampledCubemap dirs(r, s);
  const CubemapLayout layout(r);
  ASSERT_EQ(dirs.subray_count(), static_cast<std::size_t>(layout.pixel_count()) * s * s);
  std::vector<double> per_pixel(layout.pixel_count(), 0.0);
  for (std::size_t i = 0; i < dirs.subray_count(); ++i) {
    const Vec3d d = dirs.direction(i);
    EXPECT_NEAR(glm::length(d), 1.0, 1e-6);
    // Each sub-ray lies inside the pixel it is counted for.
    ASSERT_EQ(layout.pixel_of(d), dirs.pixel_of_subray(i)) << "sub-ray " << i;
    per_pixel[dirs.pixel_of_subray(i)] += dirs.solid_angles()[i];
  }
  for (int k = 0; k < layout.pixel_count(); ++k)
    ASSERT_NEAR(per_pixel[k], layout.solid_angle(k), 1e-12) << k;
  const double total = std::accumulate(dirs.solid_angles().begin(), dirs.solid_angles().end(), 0.0);
  EXPECT_NEAR(total, kFourPi, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(Sizes, SupersampledTable,
                         ::testing::Values(std::pair{1, 1}, std::pair{4, 3}, std::pair{8, 2},
                                           std::pair{32, 2}));

TEST(SupersampledCubemap, RejectsBadParameters) {
  EXPECT_THROW(SupersampledCubemap(0, 2), ParameterError);
  EXPECT_THROW(SupersampledCubemap(32, 0), ParameterError);
  EXPECT_THROW(SupersampledCubemap(32, 16), ParameterError);  // 256 sub-rays overflow a u8 count
}

TEST(EmbreeScene, SingleRayHitsAndMisses) {
  const Mesh plane = make_plane(2.0, 2.0, 1);  // y = 0, |x|, |z| <= 1
  const EmbreeScene scene(plane);
  EXPECT_TRUE(scene.occluded({0.2, 1.0, 0.3}, {0, -1, 0}));
  EXPECT_FALSE(scene.occluded({0.2, 1.0, 0.3}, {0, 1, 0}));
  EXPECT_FALSE(scene.occluded({1.5, 1.0, 0.0}, {0, -1, 0}));            // passes beside the plane
  EXPECT_FALSE(scene.occluded({0.2, 1.0, 0.3}, {0, -1, 0}, 0.0, 0.5));  // segment ends before it
  EXPECT_NEAR(scene.bounds_diagonal(), std::sqrt(8.0), 1e-6);
  EXPECT_NEAR(scene.ray_offset(), 1e-4 * std::sqrt(8.0), 1e-9);
}

TEST(EmbreeScene, RejectsEmptyMesh) {
  EXPECT_THROW(EmbreeScene(Mesh{}), ParameterError);
}

// A point on an open plane sees exactly the pixels above its tangent plane.
TEST(Visibility, OpenPlaneSeesTheUpperHemisphere) {
  // A small plane well below the point: it must not block anything above the tilted
  // tangent plane (the steepest such ray descends at 21 degrees, reaching y = 0 at 2.6).
  const Mesh plane = make_plane(1.0, 1.0, 2);
  const EmbreeScene scene(plane);
  for (int s : {1, 2, 3}) {
    const SupersampledCubemap dirs(16, s);
    const CubemapLayout layout(16);
    // A tilted normal, so that the horizon cuts through pixels.
    const Vec3d n = glm::normalize(Vec3d(0.3, 1.0, -0.2));
    std::vector<std::uint8_t> counts(layout.pixel_count());
    std::vector<std::uint32_t> unblocked;
    const std::uint64_t traced = scene.visibility(dirs, {0, 1.0, 0}, n, counts, &unblocked);

    // The tracer tests dot(d, n) > 0 in float: directions within rounding of the tangent
    // plane may go either way.
    std::uint64_t above = 0, grazing = 0;
    for (std::size_t r = 0; r < dirs.subray_count(); ++r) {
      const double dn = glm::dot(dirs.direction(r), n);
      above += dn > 1e-6;
      grazing += std::abs(dn) <= 1e-6;
    }
    EXPECT_GE(traced, above);
    EXPECT_LE(traced, above + grazing);
    EXPECT_EQ(unblocked.size(), traced);  // nothing above the tangent plane to block
    EXPECT_TRUE(std::is_sorted(unblocked.begin(), unblocked.end()));
    int straddling = 0;
    for (int k = 0; k < layout.pixel_count(); ++k) {
      int pos = 0;
      for (const Vec3d& c : pixel_corners(layout, k)) pos += glm::dot(c, n) > 0;
      if (pos == 4) {
        ASSERT_EQ(counts[k], s * s) << "pixel " << k;
      } else if (pos == 0) {
        ASSERT_EQ(counts[k], 0) << "pixel " << k;
      } else {
        ++straddling;
        ASSERT_LE(counts[k], s * s);
      }
    }
    EXPECT_GT(straddling, 0);
  }
}

// A point on a plane under a sphere: the sphere's shadow is the cone of half-angle
// asin(radius / distance). The UV sphere is a polygon inscribed in the true sphere, so it
// blocks at least the cone of its inner radius and at most the true cone; a pixel is
// decided when it lies entirely (centre angle -/+ its angular radius) on one side.
TEST(Visibility, SphereShadowMatchesTheAnalyticCone) {
  const double rho = 0.5;
  const int segments = 48, rings = 24;
  const Vec3d centre{0.25, 1.0, -0.35};
  Mesh mesh = make_plane(6.0, 6.0, 2);
  Mesh sphere = make_sphere(rho, segments, rings);
  translate(sphere, centre);
  mesh.append(sphere, 1);
  const EmbreeScene scene(mesh);

  // Every point of a triangle with vertices on the sphere lies within the angle of the
  // quad's diagonal of a vertex, so the polygon contains the ball of this radius.
  const double diag = std::hypot(kTwoPi / segments, kPi / rings);
  const double rho_in = rho * std::cos(diag);

  const Vec3d p{0, 0, 0}, n{0, 1, 0};
  const Vec3d origin = p + scene.ray_offset() * n;
  const Vec3d axis = glm::normalize(centre - origin);
  const double dist = glm::length(centre - origin);
  const double alpha_out = std::asin(rho / dist), alpha_in = std::asin(rho_in / dist);

  for (int s : {1, 2, 4}) {
    const int r = 32;
    const SupersampledCubemap dirs(r, s);
    const CubemapLayout layout(r);
    std::vector<std::uint8_t> counts(layout.pixel_count());
    scene.visibility(dirs, p, n, counts);
    int inside = 0, outside = 0, partial = 0;
    for (int k = 0; k < layout.pixel_count(); ++k) {
      const Vec3d d = layout.direction(k);
      double radius = 0.0;
      bool above = true;
      for (const Vec3d& c : pixel_corners(layout, k)) {
        radius = std::max(radius, angle_between(d, c));
        above = above && glm::dot(c, n) > 0;
      }
      const double a = angle_between(d, axis);
      if (a < alpha_in - radius) {
        ++inside;
        ASSERT_EQ(counts[k], 0) << "pixel " << k << " inside the cone, s = " << s;
      } else if (a > alpha_out + radius && above) {
        ++outside;
        ASSERT_EQ(counts[k], s * s) << "pixel " << k << " outside the cone, s = " << s;
      }
      partial += counts[k] > 0 && counts[k] < s * s;
    }
    // The test is not vacuous: a real shadow, a real sky, and fractional edge pixels.
    EXPECT_GT(inside, 50);
    EXPECT_GT(outside, 2000);
    if (s > 1) {
      EXPECT_GT(partial, 10);
    }
  }
}

}  // namespace
}  // namespace prt
