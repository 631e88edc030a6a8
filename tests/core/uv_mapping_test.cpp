#include "prtlab/geometry/uv_mapping.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "prtlab/base/error.h"
#include "prtlab/geometry/mesh_io.h"
#include "prtlab/geometry/mesh_processing.h"
#include "prtlab/geometry/procedural_shapes.h"
#include "prtlab/geometry/scene.h"

namespace prt {
namespace {
namespace fs = std::filesystem;

Mesh without_uvs(Mesh m) {
  m.uvs.clear();
  m.tangents.clear();
  return m;
}

/// Max over vertices of |uv - A p - c| for the affine map (A, c) fitted to three vertices.
double affine_residual(const Mesh& m, std::uint32_t i0, std::uint32_t i1, std::uint32_t i2) {
  // Solve uv = A (p - p0) + uv0 on the triangle's plane: with e1, e2 spanning it and n its
  // normal, A e1 = d1, A e2 = d2, A n = 0.
  const Vec3d p0(m.positions[i0]), e1 = Vec3d(m.positions[i1]) - p0,
                                   e2 = Vec3d(m.positions[i2]) - p0;
  const Vec3d n = glm::normalize(glm::cross(e1, e2));
  const Mat3d P(e1, e2, n);  // columns
  const Mat3d Pinv = glm::inverse(P);
  const Vec2d w0(m.uvs[i0]), d1 = Vec2d(m.uvs[i1]) - w0, d2 = Vec2d(m.uvs[i2]) - w0;
  double worst = 0;
  for (std::size_t v = 0; v < m.vertex_count(); ++v) {
    const Vec3d c = Pinv * (Vec3d(m.positions[v]) - p0);  // (a, b, off-plane)
    const Vec2d want = w0 + c.x * d1 + c.y * d2;
    worst = std::max(worst, glm::length(Vec2d(m.uvs[v]) - want));
  }
  return worst;
}

// A plane (in any orientation) is one chart, mapped by an exact isometry scaled by 1/extent.
TEST(UvMapping, PlaneIsAnExactAffineMap) {
  for (const Vec3d rot : {Vec3d(0, 0, 0), Vec3d(90, 0, 0), Vec3d(30, 40, 10), Vec3d(180, 0, 0)}) {
    Mesh m = without_uvs(make_plane(2.0, 3.0, 7));
    Transform xf;
    xf.rotate_deg = rot;
    xf.translate = {0.5, -1, 2};
    apply_transform(m, xf);
    UvAtlasReport r;
    const Mesh g = generate_uvs(m, {}, &r);
    EXPECT_EQ(r.charts, 1u);
    EXPECT_EQ(g.vertex_count(), m.vertex_count());  // no seams
    EXPECT_LT(affine_residual(g, g.indices[0], g.indices[1], g.indices[2]), 2e-6) << rot.x;
    const UvStretch s = measure_uv_stretch(g);
    EXPECT_EQ(s.flipped, 0u);
    EXPECT_NEAR(s.area_ratio_min, 1.0, 1e-4);
    EXPECT_NEAR(s.area_ratio_max, 1.0, 1e-4);
    EXPECT_NEAR(s.anisotropy_max, 1.0, 1e-4);
    // One UV unit is the largest side E of the bounding box; the chart's axis is the plane's
    // normal, so the plane's 2 x 3 rectangle maps to a 2/E x 3/E one (possibly rotated).
    const Vec3 ext = m.bounds().extent();
    const float E = std::max({ext.x, ext.y, ext.z});
    const auto dist = [&](std::size_t a, std::size_t b) {
      return glm::length(g.uvs[a] - g.uvs[b]) * E / glm::length(g.positions[a] - g.positions[b]);
    };
    for (std::size_t v = 1; v < g.vertex_count(); v += 5) EXPECT_NEAR(dist(0, v), 1.0f, 1e-5f);
  }
}

TEST(UvMapping, PlanarUvOrientation) {
  // Facing +z: u along +x, v along +y; facing +y: u along +x, v along -z.
  const Vec3d o(0.0);
  EXPECT_EQ(planar_uv(Vec3(0.5f, 0.25f, 9.f), {0, 0, 1}, o, 1.0), Vec2(0.5f, 0.25f));
  EXPECT_EQ(planar_uv(Vec3(0.5f, 9.f, 0.25f), {0, 1, 0}, o, 1.0), Vec2(0.5f, -0.25f));
  EXPECT_EQ(planar_uv(Vec3(2.f, 4.f, 0.f), {0, 0, 1}, Vec3d(1, 1, 0), 2.0), Vec2(0.5f, 1.5f));
}

// Bounded stretch on curved and faceted shapes: no flips, every triangle within the hard cone
// of its chart's axis, hence area ratios within 1 / cos(hard cone) of each other.
TEST(UvMapping, BoundedStretchOnSphereAndBox) {
  const UvAtlasOptions opt;
  const double bound = 1.0 / std::cos(opt.hard_cone_deg * kPi / 180.0);
  {
    const Mesh sphere = weld_vertices(make_sphere(1.0, 48, 24), WeldKey::kPosition);
    UvAtlasReport r;
    const Mesh g = generate_uvs(sphere, opt, &r);
    const UvStretch s = measure_uv_stretch(g);
    EXPECT_EQ(s.triangles, g.triangle_count());
    EXPECT_EQ(s.flipped, 0u);
    EXPECT_EQ(s.degenerate_uv, 0u);
    EXPECT_LE(r.max_angle_deg, opt.hard_cone_deg + 1e-9);
    EXPECT_LE(s.area_ratio_max / s.area_ratio_min, bound * (1 + 1e-6));
    EXPECT_LE(s.anisotropy_max, bound * (1 + 1e-6));
    EXPECT_LT(s.area_ratio_std, 0.15);  // measured 0.09
    EXPECT_GT(s.area_ratio_p05, 0.75);
    EXPECT_GE(r.charts, 6u);  // a 60-degree cone covers at most ~1/7 of the sphere
    EXPECT_LE(r.charts, 24u);
    EXPECT_LT(g.vertex_count(), sphere.vertex_count() * 13 / 10);
  }
  {
    // Every box face is its own chart (creases are never crossed) and keeps its vertices.
    const Mesh box = without_uvs(make_box(Vec3d(0.5, 0.1, 0.3), 5));
    UvAtlasReport r;
    const Mesh g = generate_uvs(box, opt, &r);
    EXPECT_EQ(r.charts, 6u);
    EXPECT_EQ(g.vertex_count(), box.vertex_count());
    EXPECT_NEAR(r.max_angle_deg, 0.0, 1e-6);
    const UvStretch s = measure_uv_stretch(g);
    EXPECT_NEAR(s.area_ratio_min, 1.0, 1e-4);
    EXPECT_NEAR(s.area_ratio_max, 1.0, 1e-4);
  }
}

// Tangents from the generated UVs (Lengyel, compute_tangents) give orthonormal right-handed
// frames whose tangent follows dp/du and bitangent dp/dv of the triangles around each vertex.
TEST(UvMapping, TangentFramesFollowTheUvGradient) {
  Mesh m = generate_uvs(weld_vertices(make_torus(0.7, 0.3, 40, 20), WeldKey::kPosition));
  compute_smooth_normals(m);
  compute_tangents(m);
  for (std::size_t v = 0; v < m.vertex_count(); ++v) {
    const LocalFrame f = m.frame(v);
    EXPECT_NEAR(glm::length(f.t), 1.0, 1e-6);
    EXPECT_NEAR(glm::length(f.b), 1.0, 1e-6);
    EXPECT_NEAR(glm::dot(f.t, f.n), 0.0, 1e-6);
    EXPECT_NEAR(glm::dot(glm::cross(f.t, f.b), f.n), 1.0, 1e-6);
  }
  double worst_t = 1, worst_b = 1;
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const std::uint32_t* i = &m.indices[3 * t];
    const Vec3d p0(m.positions[i[0]]);
    const Vec3d e1 = Vec3d(m.positions[i[1]]) - p0, e2 = Vec3d(m.positions[i[2]]) - p0;
    const Vec2d w0(m.uvs[i[0]]), d1 = Vec2d(m.uvs[i[1]]) - w0, d2 = Vec2d(m.uvs[i[2]]) - w0;
    const double det = d1.x * d2.y - d2.x * d1.y;
    ASSERT_GT(det, 0.0) << "triangle " << t << " is flipped in UV";
    const Vec3d dpdu = (e1 * d2.y - e2 * d1.y) / det;
    const Vec3d dpdv = (e2 * d1.x - e1 * d2.x) / det;
    for (int k = 0; k < 3; ++k) {
      const LocalFrame f = m.frame(i[k]);
      const auto in_plane = [&](Vec3d d) { return glm::normalize(d - glm::dot(d, f.n) * f.n); };
      worst_t = std::min(worst_t, glm::dot(in_plane(dpdu), f.t));
      worst_b = std::min(worst_b, glm::dot(in_plane(dpdv), f.b));
    }
  }
  // A vertex's tangent averages its chart's triangles, which agree to within the cone's
  // projection skew.
  EXPECT_GT(worst_t, 0.8);
  EXPECT_GT(worst_b, 0.8);
}

TEST(UvMapping, DeterministicAndValidated) {
  const Mesh m = weld_vertices(make_torus(0.7, 0.3, 24, 12), WeldKey::kPosition);
  const Mesh a = generate_uvs(m), b = generate_uvs(m);
  EXPECT_EQ(a.uvs, b.uvs);
  EXPECT_EQ(a.indices, b.indices);
  UvAtlasOptions bad;
  bad.max_cone_deg = 0;
  EXPECT_THROW(generate_uvs(m, bad), ParameterError);
  bad = {};
  bad.hard_cone_deg = bad.max_cone_deg - 1;
  EXPECT_THROW(generate_uvs(m, bad), ParameterError);
  bad = {};
  bad.min_chart_area = 1.0;
  EXPECT_THROW(generate_uvs(m, bad), ParameterError);
  EXPECT_THROW(measure_uv_stretch(without_uvs(m)), ParameterError);
}

// The stretch measure on known linear maps.
TEST(UvMapping, StretchMeasure) {
  Mesh m;
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)};
  m.indices = {0, 1, 2, 1, 3, 2};
  m.uvs = {Vec2(0, 0), Vec2(2, 0), Vec2(0, 0.5f), Vec2(2, 0.5f)};  // u = 2x, v = y / 2
  UvStretch s = measure_uv_stretch(m);
  EXPECT_EQ(s.triangles, 2u);
  EXPECT_EQ(s.flipped, 0u);
  EXPECT_NEAR(s.anisotropy_max, 4.0, 1e-6);
  EXPECT_NEAR(s.area_ratio_min, 1.0, 1e-6);  // uniform area scale normalises to 1
  m.uvs = {Vec2(0, 0), Vec2(1, 0), Vec2(0, 1), Vec2(3, 3)};
  s = measure_uv_stretch(m);
  // UV areas 0.5 and 2.5 over 3D areas 0.5 and 0.5: ratios 1 and 5, mean 3.
  EXPECT_NEAR(s.area_ratio_min, 1.0 / 3.0, 1e-6);
  EXPECT_NEAR(s.area_ratio_max, 5.0 / 3.0, 1e-6);
  m.uvs = {Vec2(0, 0), Vec2(0, 1), Vec2(1, 0), Vec2(1, 1)};  // mirrored: u = y, v = x
  s = measure_uv_stretch(m);
  EXPECT_EQ(s.flipped, 2u);
  EXPECT_EQ(measure_uv_stretch(m, 1).triangles, 0u);  // no triangle in part 1
}

// ---- scenes: where UVs are generated --------------------------------------------------------

class SceneUvs : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("prtlab_uv_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    // A mesh file without UVs: a welded, wobbly sphere (so the charts are not trivial).
    Mesh m = weld_vertices(make_sphere(1.0, 40, 20), WeldKey::kPosition);
    for (auto& p : m.positions) p *= 1.0f + 0.15f * std::sin(5.0f * p.y) * std::cos(3.0f * p.x);
    m.uvs.clear();
    m.normals.clear();
    m.tangents.clear();
    mesh_file_ = dir_ / "blob.obj";
    save_mesh_obj(m, mesh_file_);
    source_vertices_ = m.vertex_count();
  }
  void TearDown() override { fs::remove_all(dir_); }
  Scene build(const std::string& part_keys) {
    const fs::path p = dir_ / "s.toml";
    std::ofstream(p) << "[[part]]\nmesh = \"" << mesh_file_.string() << "\"\n" << part_keys;
    return load_scene(p);
  }
  fs::path dir_, mesh_file_;
  std::size_t source_vertices_ = 0;
};

TEST_F(SceneUvs, GeneratedUvsKeepTheTargetVertexCount) {
  ASSERT_FALSE(load_mesh(mesh_file_).has_uvs());
  const Scene s = build("target_vertices = 500\n");
  ASSERT_TRUE(s.mesh.has_uvs());
  EXPECT_NEAR(double(s.mesh.vertex_count()), 500.0, 1.0);
  // Seam copies share positions: fewer distinct positions than vertices.
  const auto rep = position_representatives(s.mesh);
  std::size_t distinct = 0;
  for (std::size_t v = 0; v < rep.size(); ++v) distinct += rep[v] == v;
  EXPECT_LT(distinct, s.mesh.vertex_count());
  EXPECT_EQ(measure_uv_stretch(s.mesh).flipped, 0u);
  // The tangents follow the generated UVs (not the normal-only frame).
  ASSERT_EQ(s.mesh.tangents.size(), s.mesh.vertex_count());

  // Without a target every source vertex stays (plus seam copies).
  const Scene full = build("");
  EXPECT_GT(full.mesh.vertex_count(), source_vertices_);
}

TEST_F(SceneUvs, UvScaleAndMappingKeys) {
  const Scene one = build("");
  const Scene scaled = build("uv_scale = [2.0, 3.0]\n");
  ASSERT_EQ(one.mesh.vertex_count(), scaled.mesh.vertex_count());
  for (std::size_t v = 0; v < one.mesh.vertex_count(); v += 17) {
    EXPECT_NEAR(scaled.mesh.uvs[v].x, 2.0f * one.mesh.uvs[v].x, 1e-5f);
    EXPECT_NEAR(scaled.mesh.uvs[v].y, 3.0f * one.mesh.uvs[v].y, 1e-5f);
  }
  EXPECT_EQ(scaled.desc.parts[0].uv_scale, 2.0);
  EXPECT_EQ(scaled.desc.parts[0].uv_scale_v, 3.0);
  EXPECT_THROW(build("uv_mapping = \"mesh\"\n"), InputError);  // the file has no UVs
  EXPECT_THROW(build("uv_mapping = \"cube\"\n"), InputError);
  EXPECT_THROW(build("uv_scale = [1.0]\n"), InputError);
  EXPECT_THROW(build("uv_scale = [1.0, -1.0]\n"), InputError);
}

// "planar" replaces a procedural box's per-face [0,1]^2 UVs by metric ones without adding
// vertices.
TEST_F(SceneUvs, PlanarMappingOfAProceduralBox) {
  const fs::path p = dir_ / "box.toml";
  const auto write = [&](const char* mapping) {
    std::ofstream(p) << "[[part]]\nmesh = \"procedural:box\"\nuv_mapping = \"" << mapping
                     << "\"\nparams = { hx = 0.5, hy = 0.05, hz = 0.25, n = 4 }\n";
    return load_scene(p);
  };
  const Scene own = write("mesh"), planar = write("planar");
  EXPECT_EQ(own.mesh.vertex_count(), planar.mesh.vertex_count());
  EXPECT_GT(measure_uv_stretch(own.mesh).anisotropy_max, 4.0);  // thin faces squashed
  EXPECT_NEAR(measure_uv_stretch(planar.mesh).anisotropy_max, 1.0, 1e-4);
}

}  // namespace
}  // namespace prt
