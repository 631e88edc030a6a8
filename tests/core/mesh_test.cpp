#include "prtlab/geometry/mesh.h"

#include <gtest/gtest.h>

#include <cmath>

#include "prtlab/geometry/procedural_shapes.h"

namespace prt {
namespace {

TEST(Mesh, BoundsCoverAllPositions) {
  Mesh m;
  EXPECT_EQ(m.bounds().lo, Vec3(0.f));
  m.positions = {{1, -2, 3}, {-4, 5, 0.5f}, {0, 0, -6}};
  EXPECT_EQ(m.bounds().lo, Vec3(-4, -2, -6));
  EXPECT_EQ(m.bounds().hi, Vec3(1, 5, 3));
  EXPECT_EQ(m.bounds().extent(), Vec3(5, 7, 9));
}

TEST(Mesh, SmoothNormalsMatchTheSphereAcrossItsSeamAndPoles) {
  Mesh sphere = make_sphere(1.0, 32, 16);
  const std::vector<Vec3> analytic = sphere.normals;
  sphere.normals.clear();
  compute_smooth_normals(sphere);
  ASSERT_EQ(sphere.normals.size(), sphere.vertex_count());
  for (std::size_t v = 0; v < sphere.vertex_count(); ++v) {
    EXPECT_NEAR(glm::length(sphere.normals[v]), 1.f, 1e-6f);
    // Seam and pole copies see only their own triangles; grouped by position they agree.
    EXPECT_GT(glm::dot(sphere.normals[v], analytic[v]), 0.9995f) << "vertex " << v;
  }
  const std::vector<std::uint32_t> rep = position_representatives(sphere);
  for (std::size_t v = 0; v < sphere.vertex_count(); ++v)
    EXPECT_EQ(sphere.normals[v], sphere.normals[rep[v]]);
}

TEST(Mesh, SmoothNormalsKeepSplitHardEdgesSharp) {
  Mesh box = make_box({1, 1, 1}, 2);
  const std::vector<Vec3> flat = box.normals;
  compute_smooth_normals(box);
  for (std::size_t v = 0; v < box.vertex_count(); ++v)
    EXPECT_EQ(box.normals[v], flat[v]) << "vertex " << v;
}

TEST(Mesh, SmoothNormalsAreAngleWeighted) {
  // At vertex 0 a quad's two triangles (corners of 45 degrees, area 1) meet one triangle on a
  // perpendicular face (a corner of 90 degrees, area 1/2): angle weighting gives both faces
  // equal weight, where area weighting would favour the quad.
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}};
  m.indices = {0, 1, 2, 0, 2, 3,  // z = 0, normal +z, corners of 45 + 45 degrees at vertex 0
               0, 1, 4};          // y = 0, normal -y, a corner of 90 degrees at vertex 0
  compute_smooth_normals(m);
  const Vec3 expected = glm::normalize(Vec3(0, -1, 1));
  EXPECT_NEAR(glm::dot(m.normals[0], expected), 1.f, 1e-6f);
}

TEST(Mesh, TangentsFollowUvsAndFallBackWithoutThem) {
  Mesh sphere = make_sphere(1.0, 32, 16);
  const std::vector<Vec3> analytic = sphere.tangents;
  sphere.tangents.clear();
  compute_tangents(sphere);
  for (std::size_t v = 0; v < sphere.vertex_count(); ++v) {
    EXPECT_NEAR(glm::dot(sphere.normals[v], sphere.tangents[v]), 0.f, 1e-6f);
    EXPECT_GT(glm::dot(sphere.tangents[v], analytic[v]), 0.99f) << "vertex " << v;
  }
  Mesh torus = make_torus(1.0, 0.25, 32, 16);
  const std::vector<Vec3> torus_analytic = torus.tangents;
  compute_tangents(torus);
  for (std::size_t v = 0; v < torus.vertex_count(); ++v)
    EXPECT_GT(glm::dot(torus.tangents[v], torus_analytic[v]), 0.99f) << "vertex " << v;

  Mesh no_uv = make_sphere(1.0, 16, 8);
  no_uv.uvs.clear();
  no_uv.tangents.clear();
  compute_tangents(no_uv);
  for (std::size_t v = 0; v < no_uv.vertex_count(); ++v) {
    EXPECT_NEAR(glm::length(no_uv.tangents[v]), 1.f, 1e-6f);
    EXPECT_NEAR(glm::dot(no_uv.normals[v], no_uv.tangents[v]), 0.f, 1e-6f);
    const LocalFrame f = LocalFrame::from_normal(Vec3d(no_uv.normals[v]));
    EXPECT_NEAR(glm::dot(Vec3d(no_uv.tangents[v]), f.t), 1.0, 1e-6);
  }
}

TEST(Mesh, FrameIsOrthonormalAndFollowsTheTangent) {
  const Mesh torus = make_torus(1.0, 0.25, 16, 8);
  for (std::size_t v = 0; v < torus.vertex_count(); ++v) {
    const LocalFrame f = torus.frame(v);
    EXPECT_NEAR(glm::dot(f.n, Vec3d(torus.normals[v])), 1.0, 1e-6);
    EXPECT_NEAR(glm::dot(f.t, Vec3d(torus.tangents[v])), 1.0, 1e-6);
    EXPECT_NEAR(glm::length(glm::cross(f.t, f.b) - f.n), 0.0, 1e-6);
  }
}

TEST(Mesh, AppendOffsetsIndicesShiftsPartsAndCompletesAttributes) {
  Mesh scene = make_sphere(1.0, 8, 4);
  const std::size_t sphere_vertices = scene.vertex_count(),
                    sphere_triangles = scene.triangle_count();
  Mesh bare;  // positions only, two parts of its own
  bare.positions = {{5, 0, 0}, {6, 0, 0}, {5, 1, 0}, {6, 1, 0}};
  bare.indices = {0, 1, 2, 1, 3, 2};
  bare.triangle_part = {0, 1};
  scene.append(bare, 3);
  EXPECT_EQ(scene.vertex_count(), sphere_vertices + 4);
  ASSERT_EQ(scene.triangle_count(), sphere_triangles + 2);
  EXPECT_EQ(scene.indices[3 * sphere_triangles], sphere_vertices);
  ASSERT_EQ(scene.triangle_part.size(), scene.triangle_count());
  EXPECT_EQ(scene.part_of(0), 0);
  EXPECT_EQ(scene.part_of(sphere_triangles), 3);
  EXPECT_EQ(scene.part_of(sphere_triangles + 1), 4);
  // The bare mesh got normals (+z, its winding), tangents and zero UVs.
  ASSERT_EQ(scene.normals.size(), scene.vertex_count());
  ASSERT_EQ(scene.tangents.size(), scene.vertex_count());
  ASSERT_EQ(scene.uvs.size(), scene.vertex_count());
  EXPECT_NEAR(glm::dot(scene.normals.back(), Vec3(0, 0, 1)), 1.f, 1e-6f);
  EXPECT_EQ(scene.uvs.back(), Vec2(0.f));
  EXPECT_EQ(scene.bounds().hi.x, 6.f);

  Mesh empty;
  empty.append(bare, 0);
  EXPECT_EQ(empty.positions, bare.positions);
  EXPECT_EQ(empty.triangle_part, bare.triangle_part);
  EXPECT_TRUE(empty.normals.empty());
}

}  // namespace
}  // namespace prt
