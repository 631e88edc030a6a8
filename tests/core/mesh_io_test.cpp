#include "prtlab/geometry/mesh_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/geometry/procedural_shapes.h"

namespace prt {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class MeshIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           fmt::format("prtlab_mesh_io_{}_{}", static_cast<long>(::getpid()), info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write(const std::string& name, const std::string& content) const {
    const fs::path file = dir_ / name;
    std::ofstream(file, std::ios::binary) << content;
    return file;
  }

  /// load_mesh must throw an InputError naming the file and containing every fragment.
  static void expect_input_error(const fs::path& file, const std::vector<std::string>& fragments) {
    try {
      load_mesh(file);
      ADD_FAILURE() << "no InputError for " << file;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_THAT(what, HasSubstr(file.filename().string()));
      EXPECT_EQ(e.file(), file);
      for (const std::string& f : fragments) EXPECT_THAT(what, HasSubstr(f));
    }
  }

  fs::path dir_;
};

/// A triangle as (position, uv) corners rotated so the smallest corner comes first (winding
/// kept), so that meshes compare independently of vertex and triangle order.
using Corner = std::tuple<float, float, float, float, float>;
using Tri = std::array<Corner, 3>;
std::vector<Tri> canonical_triangles(const Mesh& m) {
  std::vector<Tri> out;
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    Tri tri;
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t i = m.indices[3 * t + static_cast<std::size_t>(c)];
      const Vec3& p = m.positions[i];
      const Vec2 uv = m.has_uvs() ? m.uvs[i] : Vec2(0.f);
      tri[static_cast<std::size_t>(c)] = {p.x, p.y, p.z, uv.x, uv.y};
    }
    std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
    out.push_back(tri);
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST_F(MeshIoTest, LoadsHandWrittenOffExactly) {
  // A square pyramid: the base is one quad (fanned), comments and blank lines in between.
  const fs::path file = write("pyramid.off",
                              "OFF # a comment after the keyword\n"
                              "\n"
                              "5 5 0\n"
                              "# vertices\n"
                              "-1 0 -1\n"
                              " 1 0 -1\n"
                              " 1 0  1\n"
                              "-1 0  1\n"
                              " 0 2.5 0\n"
                              "4 0 1 2 3\n"
                              "3 1 0 4\n"
                              "3 2 1 4\n"
                              "3 3 2 4\n"
                              "3 0 3 4\n");
  MeshLoadReport report;
  const Mesh m = load_mesh(file, &report);
  const std::vector<Vec3> expected_positions = {
      {-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}, {0, 2.5f, 0}};
  EXPECT_EQ(m.positions, expected_positions);
  const std::vector<std::uint32_t> expected_indices = {0, 1, 2, 0, 2, 3, 1, 0, 4,
                                                       2, 1, 4, 3, 2, 4, 0, 3, 4};
  EXPECT_EQ(m.indices, expected_indices);
  EXPECT_FALSE(m.has_uvs());
  EXPECT_EQ(report.degenerate_dropped, 0u);
  EXPECT_EQ(report.unused_vertices_removed, 0u);
  ASSERT_EQ(m.normals.size(), 5u);
  ASSERT_EQ(m.tangents.size(), 5u);
  // The apex normal points up; the base (wound clockwise seen from above) faces down.
  EXPECT_GT(m.normals[4].y, 0.99f);
  EXPECT_LT(m.normals[0].y, 0.f);
}

TEST_F(MeshIoTest, OffCountsOnTheKeywordLineAndTextureCoordinates) {
  const fs::path file = write("st.off",
                              "STOFF 3 1 0\n"
                              "0 0 0 0.25 0.5\n"
                              "1 0 0 1 0.5\n"
                              "0 1 0 0.25 1\n"
                              "3 0 1 2\n");
  const Mesh m = load_mesh(file);
  ASSERT_TRUE(m.has_uvs());
  EXPECT_EQ(m.uvs, (std::vector<Vec2>{{0.25f, 0.5f}, {1.f, 0.5f}, {0.25f, 1.f}}));
  EXPECT_EQ(m.indices, (std::vector<std::uint32_t>{0, 1, 2}));
}

TEST_F(MeshIoTest, LoadsHandWrittenObjExactly) {
  // Two quads sharing an edge, in two objects, with a UV seam along the shared edge (the
  // right quad restarts u at 0): the seam vertices must stay split, the rest shared.
  const fs::path file = write("seam.obj",
                              "# two quads\n"
                              "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\n"
                              "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                              "o left\n"
                              "f 1/1 2/2 3/3 4/4\n"
                              "o right\n"
                              "f 2/1 5/2 6/3\n"
                              "f -5/-4 -1/-2 -4/-1\n");  // relative: vertices 2 6 3, uvs 1 3 4
  MeshLoadReport report;
  const Mesh m = load_mesh(file, &report);
  ASSERT_TRUE(m.has_uvs());
  EXPECT_EQ(m.triangle_count(), 4u);
  EXPECT_EQ(m.vertex_count(), 8u);  // 4 (left) + 4 (right: its corners at x = 1 carry other UVs)
  EXPECT_EQ(report.unused_vertices_removed, 0u);

  Mesh expected;
  expected.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                        {1, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0}};
  expected.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}, {1, 0}, {1, 1}, {0, 1}};
  // Assimp triangulates the quad 1-2-3-4 as (1,2,3),(1,3,4) or (1,2,4),(2,3,4): accept either.
  expected.indices = {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7};
  Mesh alternative = expected;
  alternative.indices = {0, 1, 3, 1, 2, 3, 4, 5, 6, 4, 6, 7};
  const auto got = canonical_triangles(m);
  EXPECT_TRUE(got == canonical_triangles(expected) || got == canonical_triangles(alternative));
}

TEST_F(MeshIoTest, TruncatedOffIsAnInputError) {
  expect_input_error(
      write("cut_faces.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n"),
      {"truncated", "header declares 4 vertices and 2 faces", "after all 4 vertices and 1 face"});
  expect_input_error(write("cut_vertices.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n"),
                     {"truncated", "header declares 4 vertices and 2 faces", "after 3 vertices"});
  expect_input_error(
      write("cut_line.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 2"),
      {"truncated", "inside face 1"});
  expect_input_error(write("cut_header.off", "OFF\n"), {"truncated"});
}

TEST_F(MeshIoTest, NonFiniteVertexIsAnInputError) {
  expect_input_error(
      write("nan.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 nan 0\n0 0 1\n3 0 1 2\n3 0 2 3\n"),
      {"vertex 2", "NaN coordinate"});
  expect_input_error(
      write("inf.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 -inf\n3 0 1 2\n3 0 2 3\n"),
      {"vertex 3", "infinite coordinate"});
  // Beyond float range: infinite once stored as float.
  expect_input_error(write("huge.off", "OFF\n3 1 0\n0 0 0\n1e39 0 0\n0 1 0\n3 0 1 2\n"),
                     {"vertex 1", "infinite coordinate"});
  expect_input_error(write("nan.obj", "v 0 0 0\nv 1 0 0\nv NaN 1 0\nf 1 2 3\n"),
                     {"vertex 2", "NaN coordinate"});
}

TEST_F(MeshIoTest, OutOfRangeIndexIsAnInputError) {
  expect_input_error(
      write("range.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 2 7\n"),
      {"face 1", "vertex 7", "4 vertices"});
  expect_input_error(write("negative.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n"),
                     {"face 0", "vertex -1"});
  expect_input_error(write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 9\n"),
                     {"face 1", "vertex 9", "defines 3"});
  expect_input_error(write("relative.obj", "v 0 0 0\nv 1 0 0\nf -1 -2 -3\n"),
                     {"face 0", "vertex -3"});
  expect_input_error(
      write("range.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
            "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n"),
      {"face 0", "vertex 5"});
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.indices = {0, 1, 2, 2, 1, 9};
  try {
    validate_mesh(m, "in-memory");
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("in-memory"));
    EXPECT_THAT(e.what(), HasSubstr("triangle 1 references vertex 9"));
  }
}

TEST_F(MeshIoTest, RandomBytesAreAnInputError) {
  std::mt19937 rng(20240611);
  std::string bytes(4096, '\0');
  for (char& c : bytes) c = static_cast<char>(rng() & 0xFF);
  // Unknown extension: assimp finds no reader and says so.
  expect_input_error(write("noise.bin", bytes), {"assimp cannot import it", "No suitable reader"});
  expect_input_error(write("noise.ply", bytes), {"assimp cannot import it"});
  expect_input_error(write("noise.off", bytes), {"not an OFF file"});
}

TEST_F(MeshIoTest, MissingFileIsAnInputError) {
  expect_input_error(dir_ / "nowhere.off", {"file not found"});
  expect_input_error(dir_ / "nowhere.obj", {"file not found"});
  expect_input_error(dir_ / "nowhere.ply", {"file not found"});
}

TEST_F(MeshIoTest, EmptyMeshIsAnInputError) {
  expect_input_error(write("zero.off", "OFF\n0 0 0\n"), {"empty mesh"});
  expect_input_error(write("blank.off", "# nothing but a comment\n"), {"empty mesh"});
  expect_input_error(write("points.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"),
                     {"empty mesh", "0 faces"});
  expect_input_error(write("vertices_only.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"),
                     {"empty mesh", "no triangles"});
  // Only degenerate triangles: empty after dropping them.
  expect_input_error(write("flat.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n"),
                     {"empty mesh", "degenerate"});
}

TEST_F(MeshIoTest, DegenerateTrianglesAreDroppedWithOneWarning) {
  // A tetrahedron (4 good triangles), then a repeated index, a zero-area (collinear) triangle,
  // a line face; vertex 4 is only used by the degenerate ones, vertex 6 by none.
  const fs::path file = write("degenerate.off",
                              "OFF\n7 7 0\n"
                              "0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                              "2 0 0\n"    // 4: collinear with 0 and 1
                              "0.5 0 0\n"  // 5: also on the x axis
                              "9 9 9\n"    // 6: unused
                              "3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n"
                              "3 0 0 3\n"  // repeated index
                              "3 0 5 4\n"  // zero area
                              "2 4 5\n");  // a line
  MeshLoadReport report;
  const int warnings_before = warning_count();
  const Mesh m = load_mesh(file, &report);
  EXPECT_EQ(warning_count(), warnings_before + 1);
  EXPECT_EQ(report.degenerate_dropped, 3u);
  EXPECT_EQ(report.first_degenerate, 4u);
  EXPECT_EQ(report.unused_vertices_removed, 3u);
  EXPECT_EQ(m.triangle_count(), 4u);
  EXPECT_EQ(m.vertex_count(), 4u);
  EXPECT_EQ(m.positions[3], Vec3(0, 0, 1));

  // A clean file warns nothing.
  const int before_clean = warning_count();
  load_mesh(write("clean.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
  EXPECT_EQ(warning_count(), before_clean);
}

TEST_F(MeshIoTest, SavedObjReadsBack) {
  const Mesh sphere = make_sphere(0.7, 12, 7);
  const fs::path file = dir_ / "sphere.obj";
  save_mesh_obj(sphere, file);
  const Mesh back = load_mesh(file);
  ASSERT_EQ(back.vertex_count(), sphere.vertex_count());
  ASSERT_EQ(back.triangle_count(), sphere.triangle_count());
  // Every triangle comes back with the same corners in the same winding. (Shortest round-trip
  // decimals are bit-exact for a correctly rounded reader; assimp's fast reader is off by
  // about 1e-23 on values near 1e-17, hence the tolerance.)
  const auto expected = canonical_triangles(sphere);
  const auto close = [](const Tri& a, const Tri& b) {
    for (std::size_t c = 0; c < 3; ++c) {
      const auto& [ax, ay, az, au, av] = a[c];
      const auto& [bx, by, bz, bu, bv] = b[c];
      if (std::abs(ax - bx) > 1e-6f || std::abs(ay - by) > 1e-6f || std::abs(az - bz) > 1e-6f ||
          au != bu || av != bv)
        return false;
    }
    return true;
  };
  for (const Tri& t : canonical_triangles(back))
    EXPECT_TRUE(
        std::any_of(expected.begin(), expected.end(), [&](const Tri& e) { return close(t, e); }));
}

}  // namespace
}  // namespace prt
