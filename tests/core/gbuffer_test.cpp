#include "prtlab/render/gbuffer.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "prtlab/base/error.h"
#include "prtlab/geometry/mesh_processing.h"
#include "prtlab/geometry/procedural_shapes.h"

namespace prt {
namespace {
namespace fs = std::filesystem;

constexpr int kSegments = 96, kRings = 48;

Vec3d view_local(const GBuffer& g, std::size_t i) {
  return {g.view_local[4 * i], g.view_local[4 * i + 1], g.view_local[4 * i + 2]};
}
Vec3d direction(const GBuffer& g, std::size_t i) {
  return {g.direction[4 * i], g.direction[4 * i + 1], g.direction[4 * i + 2]};
}

/// A unit sphere at the origin seen head-on from +z, filling about 60% of the image height.
/// Odd image sides put the centre of the middle pixel on the optical axis.
struct SphereView {
  Mesh mesh = make_sphere(1.0, kSegments, kRings);
  Camera cam;
  GBuffer g;
  SphereView() {
    cam.eye = {0, 0, 4};
    cam.target = {0, 0, 0};
    cam.fov_y_deg = 2.0 * std::asin(1.0 / 4.0) * 180.0 / kPi / 0.6;
    cam.width = 161;
    cam.height = 121;
    g = render_gbuffer(mesh, cam);
  }
};

// The hit mask is the analytic disc: every pixel whose centre ray is more than a pixel inside
// the silhouette cone hits, every one more than a pixel outside misses.
TEST(GBuffer, SphereHitMaskIsTheDisc) {
  const SphereView s;
  const double beta = std::asin(1.0 / 4.0);  // angular radius of the sphere
  const double pixel = s.cam.fov_y_deg * kPi / 180.0 / s.cam.height;
  int inside = 0, outside = 0, boundary = 0;
  for (int y = 0; y < s.cam.height; ++y) {
    for (int x = 0; x < s.cam.width; ++x) {
      const double angle = std::acos(std::clamp(-s.cam.pixel_direction(x, y).z, -1.0, 1.0));
      if (angle < beta - pixel) {
        ++inside;
        EXPECT_TRUE(s.g.hit(x, y)) << x << "," << y;
      } else if (angle > beta + pixel) {
        ++outside;
        EXPECT_FALSE(s.g.hit(x, y)) << x << "," << y;
      } else {
        ++boundary;
      }
    }
  }
  EXPECT_GT(inside, 3000);
  EXPECT_GT(outside, 3000);
  EXPECT_LT(boundary, 2 * (inside + outside) / 10);
}

// Barycentric reconstruction lands on the sphere (within the tessellation's sagitta) and on
// the pixel's ray at the reported depth.
TEST(GBuffer, BarycentricsReconstructTheHitPoint) {
  const SphereView s;
  // Every triangle's vertices are on the sphere; its interior is at most this far inside.
  const double sagitta = 1.0 - std::cos(kPi / kSegments) * std::cos(kPi / kRings);
  std::size_t hits = 0;
  for (std::size_t i = 0; i < s.g.pixel_count(); ++i) {
    const int tri = s.g.triangle[i];
    if (tri < 0) continue;
    ++hits;
    const std::uint32_t* v = &s.mesh.indices[3 * static_cast<std::size_t>(tri)];
    const double b1 = s.g.bary[2 * i], b2 = s.g.bary[2 * i + 1], b0 = 1 - b1 - b2;
    ASSERT_GE(b0, -1e-5);
    ASSERT_GE(b1, -1e-5);
    ASSERT_GE(b2, -1e-5);
    const Vec3d p = b0 * Vec3d(s.mesh.positions[v[0]]) + b1 * Vec3d(s.mesh.positions[v[1]]) +
                    b2 * Vec3d(s.mesh.positions[v[2]]);
    const double r = glm::length(p);
    EXPECT_LE(r, 1.0 + 1e-5);
    EXPECT_GE(r, 1.0 - sagitta - 1e-5);
    const Vec3d on_ray = s.cam.eye + double(s.g.depth[i]) * direction(s.g, i);
    EXPECT_NEAR(glm::length(on_ray - p), 0.0, 1e-4);
    // The visible half only.
    EXPECT_GT(p.z, 0.0);
  }
  EXPECT_EQ(hits, s.g.hit_count());
}

// At the centre pixel the eye is straight above the surface: e = (0, 0, 1) in the local frame.
// Elsewhere e.z is the cosine between the eye direction and the sphere's normal.
TEST(GBuffer, LocalViewDirection) {
  const SphereView s;
  // Interpolated vertex normals deviate from the radial direction by at most about a
  // triangle's angular size.
  const double tess = 2.0 * kPi / kSegments;
  const std::size_t c = s.g.index(s.cam.width / 2, s.cam.height / 2);
  ASSERT_GE(s.g.triangle[c], 0);
  const Vec3d e = view_local(s.g, c);
  EXPECT_NEAR(glm::length(e), 1.0, 1e-5);
  EXPECT_GT(e.z, std::cos(tess));
  EXPECT_LT(std::hypot(e.x, e.y), std::sin(tess));
  double worst = 0;
  for (std::size_t i = 0; i < s.g.pixel_count(); ++i) {
    if (s.g.triangle[i] < 0) continue;
    const Vec3d d = direction(s.g, i);
    const Vec3d p = s.cam.eye + double(s.g.depth[i]) * d;
    const double cos_true = glm::dot(-d, glm::normalize(p));
    worst = std::max(worst, std::abs(view_local(s.g, i).z - cos_true));
    EXPECT_NEAR(glm::length(view_local(s.g, i)), 1.0, 1e-5);
  }
  // Linear interpolation of unit normals errs to second order in the triangle's size.
  EXPECT_LT(worst, tess * tess / 4);
}

// Misses carry the background direction and the documented fill values; direction is the
// camera's pixel direction everywhere.
TEST(GBuffer, MissesAndDirections) {
  const SphereView s;
  for (int y = 0; y < s.cam.height; y += 7) {
    for (int x = 0; x < s.cam.width; x += 5) {
      const std::size_t i = s.g.index(x, y);
      EXPECT_NEAR(glm::length(direction(s.g, i) - s.cam.pixel_direction(x, y)), 0.0, 1e-6);
      EXPECT_EQ(s.g.direction[4 * i + 3], 0.f);
      if (s.g.hit(x, y)) continue;
      EXPECT_EQ(s.g.triangle[i], -1);
      EXPECT_EQ(s.g.part[i], -1);
      EXPECT_TRUE(std::isinf(s.g.depth[i]));
      EXPECT_EQ(view_local(s.g, i), Vec3d(0.0));
    }
  }
}

// A plane seen from above: UV is the plane's affine parametrisation of the hit point, and the
// local frame is (t, b, n) = (+x, -z, +y), so e_local = (e.x, -e.z, e.y) exactly.
TEST(GBuffer, PlaneUvAndFrame) {
  const Mesh plane = make_plane(2.0, 3.0, 6);
  Camera cam;
  cam.eye = {0.3, 2.0, 0.4};
  cam.target = {0, 0, 0};
  cam.up = {0, 0, -1};
  cam.fov_y_deg = 70;
  cam.width = 64;
  cam.height = 48;
  const GBuffer g = render_gbuffer(plane, cam);
  ASSERT_GT(g.hit_count(), 1000u);
  for (std::size_t i = 0; i < g.pixel_count(); ++i) {
    if (g.triangle[i] < 0) continue;
    const Vec3d d = direction(g, i);
    const Vec3d p = cam.eye + double(g.depth[i]) * d;
    EXPECT_NEAR(p.y, 0.0, 1e-5);
    EXPECT_NEAR(g.uv[2 * i], p.x / 2.0 + 0.5, 1e-5);
    EXPECT_NEAR(g.uv[2 * i + 1], 0.5 - p.z / 3.0, 1e-5);
    const Vec3d e = -d;
    const Vec3d want(e.x, -e.z, e.y);
    EXPECT_NEAR(glm::length(view_local(g, i) - want), 0.0, 1e-5);
    EXPECT_NEAR(g.normal[4 * i + 1], 1.0f, 1e-6f);
  }
}

// A sphere (part 0) left of the origin and a box (part 1) right of it, the box raised by
// `box_lift`.
Mesh sphere_and_box(int segments, int rings, double box_lift) {
  Mesh left = make_sphere(0.5, segments, rings), right = make_box(Vec3d(0.4), 2);
  Transform xf;
  xf.translate = {-0.7, 0, 0};
  apply_transform(left, xf);
  xf.translate = {0.7, box_lift, 0};
  apply_transform(right, xf);
  Mesh scene;
  scene.append(left, 0);
  scene.append(right, 1);
  return scene;
}

// Parts come from the mesh's triangle parts; two traces of one tracer agree bit for bit.
TEST(GBuffer, PartsAndDeterminism) {
  const Mesh scene = sphere_and_box(24, 12, 0.0);
  Camera cam;
  cam.eye = {0, 0, 5};
  cam.width = 80;
  cam.height = 40;
  cam.fov_y_deg = 30;
  const GBufferTracer tracer(scene);
  const GBuffer a = tracer.trace(cam), b = tracer.trace(cam);
  EXPECT_EQ(a.triangle, b.triangle);
  EXPECT_EQ(a.view_local, b.view_local);
  EXPECT_EQ(a.uv, b.uv);
  int parts[2] = {0, 0};
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      const std::size_t i = a.index(x, y);
      if (a.triangle[i] < 0) continue;
      EXPECT_EQ(a.part[i], scene.part_of(static_cast<std::size_t>(a.triangle[i])));
      EXPECT_EQ(a.part[i], x < cam.width / 2 ? 0 : 1) << x << "," << y;
      ++parts[a.part[i]];
    }
  }
  EXPECT_GT(parts[0], 100);
  EXPECT_GT(parts[1], 100);
}

// The cameras the traced paths are compared on: the mesh small in the image (most pixels
// outside its window), partly outside the image, the eye inside the bounding box of
// sphere_and_box (no window: every pixel traced), and a non-multiple-of-4 image size.
std::vector<Camera> reference_cameras() {
  std::vector<Camera> cams(4);
  cams[0].eye = {0, 0, 7};
  cams[0].width = 203;
  cams[0].height = 97;
  cams[1].eye = {2.5, 0.5, 2};
  cams[1].target = {1.5, 0, 0};
  cams[2].eye = {0.2, 0.1, 0.1};  // inside the box of the union: every pixel traced
  cams[2].target = {-0.7, 0, 0};
  cams[2].fov_y_deg = 100;
  cams[3].eye = {0.3, 3, 3};
  cams[3].width = 64;
  cams[3].height = 48;
  return cams;
}

// The packet tracer (the default) against one rtcIntersect1 per pixel: the same triangle at
// every pixel, barycentrics and depths to float rounding, the same frames. Cameras: the mesh
// small in the image (most pixels outside its window), partly outside the image, the eye
// inside the bounding box (no window), and a non-multiple-of-4 image size.
TEST(GBuffer, PacketsEqualSingleRays) {
  const Mesh scene = sphere_and_box(40, 20, 0.2);
  const GBufferTracer tracer(scene);
  const std::vector<Camera> cams = reference_cameras();
  GBuffer reused;
  for (std::size_t c = 0; c < cams.size(); ++c) {
    const GBuffer a = tracer.trace(cams[c], PrimaryRays::kSingle);
    tracer.trace(cams[c], reused, PrimaryRays::kPackets);
    const GBuffer& b = reused;
    ASSERT_EQ(a.pixel_count(), b.pixel_count());
    std::size_t hits = 0;
    for (std::size_t i = 0; i < a.pixel_count(); ++i) {
      ASSERT_EQ(a.triangle[i], b.triangle[i]) << "camera " << c << " pixel " << i;
      EXPECT_EQ(a.part[i], b.part[i]);
      for (int k = 0; k < 4; ++k) EXPECT_EQ(a.direction[4 * i + k], b.direction[4 * i + k]);
      if (a.triangle[i] < 0) {
        EXPECT_TRUE(std::isinf(b.depth[i]));
        continue;
      }
      ++hits;
      for (int k = 0; k < 2; ++k) {
        EXPECT_NEAR(a.bary[2 * i + k], b.bary[2 * i + k], 1e-6f) << c << " " << i;
        EXPECT_NEAR(a.uv[2 * i + k], b.uv[2 * i + k], 1e-5f) << c << " " << i;
      }
      EXPECT_NEAR(a.depth[i], b.depth[i], 1e-6f * a.depth[i]);
      for (int k = 0; k < 4; ++k) {
        EXPECT_NEAR(a.view_local[4 * i + k], b.view_local[4 * i + k], 1e-5f) << c << " " << i;
        EXPECT_NEAR(a.normal[4 * i + k], b.normal[4 * i + k], 1e-5f) << c << " " << i;
      }
    }
    EXPECT_GT(hits, a.pixel_count() / 100) << "camera " << c;
    EXPECT_LT(hits, a.pixel_count()) << "camera " << c;
  }
}

// The rasteriser against one ray per pixel centre on the cameras above. A pixel centre within
// rounding of an edge may go to either neighbour (or, on a silhouette, hit in one and miss in
// the other): where the two disagree, the centre must lie within 1e-3 (in barycentrics) of an
// edge of the triangle each found, and such pixels are few. Everywhere else: the same triangle,
// barycentrics and depth to float rounding, the same frames. The eye inside the box (camera 2)
// has vertices behind it: the rasteriser hands over to packets, which equal single rays.
TEST(GBuffer, RasterEqualsSingleRaysAwayFromEdges) {
  const Mesh scene = sphere_and_box(40, 20, 0.2);
  const GBufferTracer tracer(scene);
  const std::vector<Camera> cams = reference_cameras();
  const auto near_edge = [](const GBuffer& g, std::size_t i) {
    if (g.triangle[i] < 0) return false;
    const float b1 = g.bary[2 * i], b2 = g.bary[2 * i + 1];
    return std::min({b1, b2, 1.f - b1 - b2}) < 1e-3f;
  };
  const auto hit_point = [](const Mesh& m, const GBuffer& g, std::size_t i) {
    const std::size_t t = static_cast<std::size_t>(g.triangle[i]);
    const double b1 = g.bary[2 * i], b2 = g.bary[2 * i + 1];
    return (1 - b1 - b2) * Vec3d(m.positions[m.indices[3 * t]]) +
           b1 * Vec3d(m.positions[m.indices[3 * t + 1]]) +
           b2 * Vec3d(m.positions[m.indices[3 * t + 2]]);
  };
  double worst = 0;
  GBuffer reused;
  for (std::size_t c = 0; c < cams.size(); ++c) {
    const GBuffer a = tracer.trace(cams[c], PrimaryRays::kSingle);
    tracer.trace(cams[c], reused, PrimaryRays::kRaster);
    const GBuffer& b = reused;
    ASSERT_EQ(a.pixel_count(), b.pixel_count());
    std::size_t hits = 0, disagree = 0;
    for (std::size_t i = 0; i < a.pixel_count(); ++i) {
      for (int k = 0; k < 4; ++k) EXPECT_EQ(a.direction[4 * i + k], b.direction[4 * i + k]);
      if (a.triangle[i] != b.triangle[i]) {
        ++disagree;
        EXPECT_NE(c, 2u) << "the eye inside the box: packets, which equal single rays";
        EXPECT_TRUE((a.triangle[i] < 0 || near_edge(a, i)) &&
                    (b.triangle[i] < 0 || near_edge(b, i)))
            << "camera " << c << " pixel " << i << ": triangles " << a.triangle[i] << " and "
            << b.triangle[i] << " away from an edge";
        continue;
      }
      EXPECT_EQ(a.part[i], b.part[i]);
      if (a.triangle[i] < 0) {
        EXPECT_TRUE(std::isinf(b.depth[i]));
        continue;
      }
      ++hits;
      // The hit points, not the barycentrics, to the ray tracer's rounding: its ray direction
      // is rounded to float (a relative 2^-24 a component, moving the hit by as much of the
      // depth), its origin too (of |eye|), and Embree intersects in float (ulps of |P|); the
      // rasteriser is exact but for double rounding. Over a small triangle the same distance
      // is a larger difference of barycentrics.
      const Vec3d pa = hit_point(scene, a, i), pb = hit_point(scene, b, i);
      const double bound =
          8 * 0x1p-24 *
          (static_cast<double>(a.depth[i]) + glm::length(cams[c].eye) + glm::length(pa));
      EXPECT_LE(glm::length(pa - pb), bound) << c << " " << i;
      worst = std::max(worst, glm::length(pa - pb) / bound);
      EXPECT_NEAR(a.depth[i], b.depth[i], 1e-5f * a.depth[i]);
      for (int k = 0; k < 4; ++k) {
        EXPECT_NEAR(a.view_local[4 * i + k], b.view_local[4 * i + k], 1e-4f) << c << " " << i;
        EXPECT_NEAR(a.normal[4 * i + k], b.normal[4 * i + k], 1e-4f) << c << " " << i;
      }
    }
    EXPECT_GT(hits, a.pixel_count() / 100) << "camera " << c;
    // The band within 1e-3 of an edge is a small share of the covered pixels.
    EXPECT_LE(disagree, hits / 50 + 2) << "camera " << c;
  }
  std::printf("worst hit-point difference: %.3f of the bound\n", worst);
}

TEST(GBuffer, DebugImages) {
  const SphereView s;
  const RgbImage n = gbuffer_image(s.g, GBufferView::kNormal);
  ASSERT_EQ(n.width, s.cam.width);
  ASSERT_EQ(n.height, s.cam.height);
  EXPECT_EQ(n.at(0, 0), Rgb(0.f));  // background
  const Rgb c = n.at(s.cam.width / 2, s.cam.height / 2);
  EXPECT_NEAR(c.z, 1.0f, 0.01f);  // normal (0, 0, 1) -> (0.5, 0.5, 1)
  EXPECT_NEAR(c.x, 0.5f, 0.05f);
  const RgbImage checker = gbuffer_image(s.g, GBufferView::kUvChecker);
  float lo = 1, hi = 0;
  for (const Rgb& p : checker.pixels) {
    EXPECT_GE(glm::min(p.x, glm::min(p.y, p.z)), 0.f);
    EXPECT_LE(glm::max(p.x, glm::max(p.y, p.z)), 1.f);
    if (p != Rgb(0.f)) lo = std::min(lo, p.y), hi = std::max(hi, p.y);
  }
  EXPECT_GT(hi - lo, 0.3f);  // both checker colours appear
  const fs::path file =
      fs::temp_directory_path() / ("prtlab_gbuffer_test_" + std::to_string(::getpid()) + ".png");
  write_gbuffer_png(s.g, GBufferView::kUvChecker, file);
  EXPECT_GT(fs::file_size(file), 100u);
  fs::remove(file);
}

TEST(GBuffer, RejectsEmptyMeshAndBadCamera) {
  EXPECT_THROW(GBufferTracer(Mesh{}), ParameterError);
  const GBufferTracer t(make_box(Vec3d(0.5), 1));
  Camera bad;
  bad.fov_y_deg = -1;
  EXPECT_THROW(t.trace(bad), ParameterError);
}

}  // namespace
}  // namespace prt
