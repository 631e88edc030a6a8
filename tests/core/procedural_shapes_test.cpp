#include "prtlab/geometry/procedural_shapes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/geometry/mesh_processing.h"

namespace prt {
namespace {

struct Measures {
  double area = 0.0;
  double volume = 0.0;  ///< divergence theorem: sum of signed tetrahedra to the origin
};

Measures measure(const Mesh& m) {
  Measures out;
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const Vec3d a(m.positions[m.indices[3 * t]]), b(m.positions[m.indices[3 * t + 1]]),
        c(m.positions[m.indices[3 * t + 2]]);
    out.area += 0.5 * glm::length(glm::cross(b - a, c - a));
    out.volume += glm::dot(a, glm::cross(b, c)) / 6.0;
  }
  return out;
}

/// Edges used by one triangle (border) and by more than two (non-manifold), by index.
std::pair<std::size_t, std::size_t> open_and_non_manifold_edges(const Mesh& m) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (std::size_t t = 0; t < m.triangle_count(); ++t)
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t a = m.indices[3 * t + static_cast<std::size_t>(c)];
      const std::uint32_t b = m.indices[3 * t + static_cast<std::size_t>((c + 1) % 3)];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  std::size_t border = 0, other = 0;
  for (const auto& [edge, n] : uses) {
    border += n == 1;
    other += n > 2;
  }
  return {border, other};
}

struct Shape {
  std::string name;
  std::function<Mesh()> make;
  bool closed;
};

std::vector<Shape> shapes() {
  return {
      {"sphere", [] { return make_sphere(1.25, 24, 12); }, true},
      {"plane", [] { return make_plane(2.0, 3.0, 5); }, false},
      {"box",
       [] {
         return make_box({0.5, 1.0, 1.5}, 3);
       },
       true},
      {"torus", [] { return make_torus(1.0, 0.3, 24, 12); }, true},
      {"cylinder", [] { return make_cylinder(0.5, 2.0, 20, 3); }, true},
  };
}

TEST(ProceduralShapes, SphereAreaAndVolumeConvergeFromBelow) {
  const double r = 1.5;
  double previous_error = 1.0;
  for (const int segments : {16, 32, 64}) {
    const Measures m = measure(make_sphere(r, segments, segments / 2));
    const double area = 4.0 * kPi * r * r, volume = 4.0 / 3.0 * kPi * r * r * r;
    // An inscribed polyhedron falls short by O(h^2), h = 2 pi / segments the angular spacing
    // (the rings have the same): about 0.21 h^2 in area and 0.41 h^2 in volume.
    const double h2 = std::pow(kTwoPi / segments, 2);
    EXPECT_LT(m.area, area);
    EXPECT_LT(m.volume, volume);
    EXPECT_GT(m.area, area * (1.0 - 0.25 * h2)) << segments;
    EXPECT_GT(m.volume, volume * (1.0 - 0.5 * h2)) << segments;
    const double error = 1.0 - m.volume / volume;
    EXPECT_LT(error, 0.3 * previous_error) << "second-order convergence";
    previous_error = error;
  }
}

TEST(ProceduralShapes, TorusAndCylinderVolumes) {
  const double R = 1.0, r = 0.3;
  const Measures torus = measure(make_torus(R, r, 64, 32));
  EXPECT_NEAR(torus.volume / (2.0 * kPi * kPi * R * r * r), 1.0, 0.01);
  EXPECT_NEAR(torus.area / (4.0 * kPi * kPi * R * r), 1.0, 0.01);
  const Measures cylinder = measure(make_cylinder(0.5, 2.0, 64, 4));
  EXPECT_NEAR(cylinder.volume / (kPi * 0.25 * 2.0), 1.0, 0.01);
  EXPECT_NEAR(cylinder.area / (2.0 * kPi * 0.5 * 2.0 + 2.0 * kPi * 0.25), 1.0, 0.01);
  const Measures box = measure(make_box({0.5, 1.0, 1.5}, 2));
  EXPECT_NEAR(box.volume, 6.0, 1e-5);
  EXPECT_NEAR(box.area, 2.0 * (1 * 2 + 2 * 3 + 1 * 3), 1e-5);
  EXPECT_NEAR(measure(make_plane(2.0, 3.0, 4)).area, 6.0, 1e-5);
}

TEST(ProceduralShapes, NormalsAreUnitAndOutwardTangentsOrthogonalUvsRightHanded) {
  for (const Shape& shape : shapes()) {
    SCOPED_TRACE(shape.name);
    const Mesh m = shape.make();
    ASSERT_EQ(m.normals.size(), m.vertex_count());
    ASSERT_EQ(m.tangents.size(), m.vertex_count());
    ASSERT_EQ(m.uvs.size(), m.vertex_count());
    for (std::size_t v = 0; v < m.vertex_count(); ++v) {
      EXPECT_NEAR(glm::length(m.normals[v]), 1.f, 1e-6f);
      EXPECT_NEAR(glm::length(m.tangents[v]), 1.f, 1e-6f);
      EXPECT_NEAR(glm::dot(m.normals[v], m.tangents[v]), 0.f, 1e-6f);
    }
    for (std::size_t t = 0; t < m.triangle_count(); ++t) {
      const std::uint32_t* i = &m.indices[3 * t];
      const Vec3d p0(m.positions[i[0]]);
      const Vec3d e1 = Vec3d(m.positions[i[1]]) - p0, e2 = Vec3d(m.positions[i[2]]) - p0;
      const Vec3d face = glm::normalize(glm::cross(e1, e2));
      // Winding agrees with the normals (counter-clockwise seen from the front).
      for (int c = 0; c < 3; ++c)
        EXPECT_GT(glm::dot(face, Vec3d(m.normals[i[c]])), 0.3) << "triangle " << t;
      // dp/du and dp/dv of the triangle: the tangent follows +u, and n x t follows +v.
      const Vec2d w0(m.uvs[i[0]]), d1 = Vec2d(m.uvs[i[1]]) - w0, d2 = Vec2d(m.uvs[i[2]]) - w0;
      const double det = d1.x * d2.y - d2.x * d1.y;
      ASSERT_GT(std::abs(det), 0.0);
      const Vec3d dpdu = (e1 * d2.y - e2 * d1.y) / det, dpdv = (e2 * d1.x - e1 * d2.x) / det;
      EXPECT_GT(det, 0.0) << "UVs wound like the positions";
      for (int c = 0; c < 3; ++c) {
        const Vec3d n(m.normals[i[c]]), tan(m.tangents[i[c]]);
        EXPECT_GT(glm::dot(tan, glm::normalize(dpdu)), 0.5) << "triangle " << t;
        EXPECT_GT(glm::dot(glm::cross(n, tan), glm::normalize(dpdv)), 0.5) << "triangle " << t;
      }
    }
    // Closed shapes enclose positive volume (outward winding); the analytic normals point away
    // from the centre of a sphere.
    if (shape.closed) {
      EXPECT_GT(measure(m).volume, 0.0);
    }
  }
  const Mesh sphere = make_sphere(2.0, 16, 8);
  for (std::size_t v = 0; v < sphere.vertex_count(); ++v)
    EXPECT_NEAR(glm::dot(Vec3d(sphere.normals[v]), glm::normalize(Vec3d(sphere.positions[v]))), 1.0,
                1e-6);
}

TEST(ProceduralShapes, ClosedShapesCloseWhenWelded) {
  for (const Shape& shape : shapes()) {
    SCOPED_TRACE(shape.name);
    const Mesh m = shape.make();
    const auto [open_before, bad_before] = open_and_non_manifold_edges(m);
    EXPECT_EQ(bad_before, 0u);
    const Mesh welded = weld_vertices(m, WeldKey::kPosition);
    const auto [open, bad] = open_and_non_manifold_edges(welded);
    EXPECT_EQ(bad, 0u);
    if (shape.closed) {
      EXPECT_EQ(open, 0u) << "every edge shared by two triangles";
      EXPECT_GT(open_before, 0u) << "(the unwelded shape has seams)";
    } else {
      EXPECT_EQ(open, 4u * 5u);  // the plane's outline: 4 sides of 5 quads
    }
  }
  // Exact counts after welding: a box of n x n quads per face has 6 n^2 + 2 vertices; a
  // UV sphere segments x (rings - 1) + 2.
  EXPECT_EQ(weld_vertices(make_box({1, 2, 3}, 3), WeldKey::kPosition).vertex_count(), 6u * 9u + 2u);
  EXPECT_EQ(weld_vertices(make_sphere(1, 24, 12), WeldKey::kPosition).vertex_count(),
            24u * 11u + 2u);
  EXPECT_EQ(make_sphere(1, 24, 12).vertex_count(), 25u * 11u + 2u * 24u);
  EXPECT_EQ(weld_vertices(make_torus(1, 0.3, 24, 12), WeldKey::kPosition).vertex_count(),
            24u * 12u);
}

TEST(ProceduralShapes, InvalidParametersAreParameterErrors) {
  EXPECT_THROW(make_sphere(-1.0, 16, 8), ParameterError);
  EXPECT_THROW(make_sphere(1.0, 2, 8), ParameterError);
  EXPECT_THROW(make_sphere(1.0, 16, 1), ParameterError);
  EXPECT_THROW(make_plane(0.0, 1.0, 4), ParameterError);
  EXPECT_THROW(make_plane(1.0, 1.0, 0), ParameterError);
  EXPECT_THROW(make_box({1.0, std::nan(""), 1.0}, 2), ParameterError);
  EXPECT_THROW(make_torus(0.3, 1.0, 16, 8), ParameterError);
  EXPECT_THROW(make_cylinder(1.0, -2.0, 16, 2), ParameterError);
}

}  // namespace
}  // namespace prt
