// Cutting one model file into scene parts by material or object group, and the clean-up such
// parts get (welding, consistent winding, linear subdivision). Every mesh here is written by
// the test itself: nothing needs the downloaded chair or temple.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/geometry/mesh_io.h"
#include "prtlab/geometry/mesh_processing.h"
#include "prtlab/geometry/procedural_shapes.h"
#include "prtlab/geometry/scene.h"
#include "support/temp_dir.h"

namespace prt {
namespace {
namespace fs = std::filesystem;

// Two unit squares side by side in the y = 0 plane (facing +y), then a third square standing
// on x = 2 (facing +x). Square A is object "left" with material "wood"; B is object "right"
// with material "wood" again (a second usemtl of the same name); C is object "right" with
// material "paint". Every vertex is written once per square, as exporters do at seams.
constexpr const char* kObj = R"(mtllib two.mtl
o left
v 0 0 0
v 0 0 -1
v 1 0 -1
v 1 0 0
usemtl wood
f 1 4 3
f 1 3 2
o right
v 1 0 0
v 1 0 -1
v 2 0 -1
v 2 0 0
usemtl wood
f 5 8 7
f 5 7 6
v 2 0 0
v 2 0 -1
v 2 1 -1
v 2 1 0
usemtl paint
f 9 10 11
f 9 11 12
)";
constexpr const char* kMtl = R"(newmtl wood
Kd 0.5 0.3 0.1
newmtl paint
Kd 0.8 0.8 0.8
)";

class MeshGroups : public ::testing::Test {
 protected:
  void SetUp() override {
    std::ofstream(dir_ / "two.obj") << kObj;
    std::ofstream(dir_ / "two.mtl") << kMtl;
  }
  fs::path obj() const { return dir_ / "two.obj"; }
  /// Writes a scene whose parts are given as TOML text, each naming the model as MODEL.
  fs::path scene(const std::string& parts) {
    std::string text = parts;
    for (std::size_t at; (at = text.find("MODEL")) != std::string::npos;)
      text.replace(at, 5, obj().string());
    const fs::path p = dir_ / "s.toml";
    std::ofstream(p) << text;
    return p;
  }
  /// Building the scene must fail with an InputError containing every one of `needles`.
  void expect_build_error(const std::string& parts, const std::vector<std::string>& needles) {
    const fs::path p = scene(parts);
    try {
      load_scene(p);
      FAIL() << "built:\n" << parts;
    } catch (const InputError& e) {
      for (const auto& n : needles)
        EXPECT_NE(std::string(e.what()).find(n), std::string::npos)
            << "expected '" << n << "' in: " << e.what();
    }
  }
  testing::TempDir dir_{"mesh_groups"};
};

std::map<std::string, std::size_t> triangles_per_group(const GroupedMesh& g) {
  std::map<std::string, std::size_t> out;
  for (std::size_t t = 0; t < g.mesh.triangle_count(); ++t) ++out[g.groups[g.mesh.part_of(t)]];
  return out;
}

TEST_F(MeshGroups, LoadsMaterialAndObjectGroups) {
  const GroupedMesh by_material = load_mesh_groups(obj(), MeshGroupKey::kMaterial);
  EXPECT_EQ(by_material.groups, (std::vector<std::string>{"wood", "paint"}));
  EXPECT_EQ(triangles_per_group(by_material),
            (std::map<std::string, std::size_t>{{"wood", 4}, {"paint", 2}}));

  const GroupedMesh by_object = load_mesh_groups(obj(), MeshGroupKey::kObject);
  EXPECT_EQ(by_object.groups, (std::vector<std::string>{"left", "right"}));
  EXPECT_EQ(triangles_per_group(by_object),
            (std::map<std::string, std::size_t>{{"left", 2}, {"right", 4}}));
  ASSERT_EQ(by_object.mesh.normals.size(), by_object.mesh.vertex_count());
}

TEST_F(MeshGroups, OffFilesHaveNoGroups) {
  const fs::path off = dir_ / "t.off";
  std::ofstream(off) << "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  EXPECT_THROW(load_mesh_groups(off, MeshGroupKey::kMaterial), InputError);
}

TEST(SelectParts, KeepsTheChosenTrianglesAndOnlyTheirVertices) {
  Mesh m = make_plane(1.0, 1.0, 2);  // 9 vertices, 8 triangles
  m.triangle_part.assign(m.triangle_count(), 0);
  for (std::size_t t = 4; t < 8; ++t) m.triangle_part[t] = 3;
  m.triangle_part[0] = 7;
  const std::uint16_t wanted[] = {3, 7};
  const Mesh s = select_parts(m, wanted);
  EXPECT_EQ(s.triangle_count(), 5u);
  EXPECT_TRUE(s.triangle_part.empty());
  EXPECT_TRUE(s.normals.empty());
  ASSERT_EQ(s.uvs.size(), s.vertex_count());
  std::set<std::uint32_t> used(s.indices.begin(), s.indices.end());
  EXPECT_EQ(used.size(), s.vertex_count());  // no vertex left unused
  // Every selected triangle comes through with its positions and UVs.
  std::size_t k = 0;
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    if (m.triangle_part[t] != 3 && m.triangle_part[t] != 7) continue;
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t a = m.indices[3 * t + static_cast<std::size_t>(c)];
      const std::uint32_t b = s.indices[3 * k + static_cast<std::size_t>(c)];
      EXPECT_EQ(m.positions[a], s.positions[b]);
      EXPECT_EQ(m.uvs[a], s.uvs[b]);
    }
    ++k;
  }
  const std::uint16_t none[] = {9};
  EXPECT_EQ(select_parts(m, none).triangle_count(), 0u);
}

double signed_volume(const Mesh& m) {
  double v = 0.0;
  for (std::size_t t = 0; t < m.triangle_count(); ++t)
    v += glm::dot(Vec3d(m.positions[m.indices[3 * t]]),
                  glm::cross(Vec3d(m.positions[m.indices[3 * t + 1]]),
                             Vec3d(m.positions[m.indices[3 * t + 2]])));
  return v / 6.0;
}

/// Directed edges used twice in the same direction: zero when the winding is consistent.
std::size_t inconsistent_edges(const Mesh& m) {
  std::set<std::pair<std::uint32_t, std::uint32_t>> seen;
  std::size_t bad = 0;
  for (std::size_t t = 0; t < m.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = m.indices[3 * t + static_cast<std::size_t>(k)];
      const std::uint32_t b = m.indices[3 * t + static_cast<std::size_t>((k + 1) % 3)];
      if (!seen.insert({a, b}).second) ++bad;
    }
  return bad;
}

void flip(Mesh& m, std::size_t t) {
  std::swap(m.indices[3 * t + 1], m.indices[3 * t + 2]);
}

TEST(OrientConsistently, RepairsFlippedFacesOfAClosedBoxAndTurnsItOutwards) {
  const Mesh box = weld_vertices(make_box({0.5, 0.5, 0.5}, 2), WeldKey::kPosition);
  const double volume = signed_volume(box);
  ASSERT_NEAR(volume, 1.0, 1e-6);
  ASSERT_EQ(inconsistent_edges(box), 0u);

  Mesh damaged = box;
  flip(damaged, 0);
  flip(damaged, 5);
  flip(damaged, 17);
  EXPECT_EQ(orient_consistently(damaged), 3u);
  EXPECT_EQ(damaged.indices, box.indices);

  // An inside-out box: every face agrees with its neighbours, yet the box faces inwards.
  Mesh inside_out = box;
  for (std::size_t t = 0; t < inside_out.triangle_count(); ++t) flip(inside_out, t);
  EXPECT_EQ(orient_consistently(inside_out), box.triangle_count());
  EXPECT_NEAR(signed_volume(inside_out), volume, 1e-6);
}

TEST(OrientConsistently, OpenSurfacesKeepTheMajorityOrientation) {
  Mesh plane = make_plane(1.0, 1.0, 4);  // 32 triangles facing +y
  plane.normals.clear();
  plane.tangents.clear();
  const Mesh reference = plane;
  flip(plane, 3);
  flip(plane, 20);
  EXPECT_EQ(orient_consistently(plane), 2u);
  EXPECT_EQ(plane.indices, reference.indices);
  EXPECT_EQ(orient_consistently(plane), 0u);  // nothing left to do

  // Seam copies (same position, own index) still connect the two halves of a component.
  Mesh split = reference;
  const std::uint32_t copy = static_cast<std::uint32_t>(split.positions.size());
  split.positions.push_back(split.positions[split.indices[0]]);
  split.uvs.push_back(Vec2(5.f));
  split.indices[0] = copy;
  flip(split, 0);
  EXPECT_EQ(orient_consistently(split), 1u);
  for (std::size_t t = 0; t < split.triangle_count(); ++t) {
    const Vec3 a = split.positions[split.indices[3 * t]];
    const Vec3 n = glm::cross(split.positions[split.indices[3 * t + 1]] - a,
                              split.positions[split.indices[3 * t + 2]] - a);
    EXPECT_GT(n.y, 0.f) << "triangle " << t;
  }
}

/// Distance of p from the surface of the axis-aligned box of half-sides h.
double box_distance(const Vec3& p, const Vec3d& h) {
  const Vec3d q = glm::abs(Vec3d(p)) - h;
  const double outside = glm::length(glm::max(q, Vec3d(0.0)));
  return outside > 0.0 ? outside : -std::max({q.x, q.y, q.z});
}

TEST(LinearSubdivision, StaysOnTheSurfaceAndGainsOneVertexPerEdge) {
  const Vec3d h{0.5, 0.2, 0.3};
  const Mesh box = weld_vertices(make_box(h, 1), WeldKey::kPosition);  // 8 vertices
  ASSERT_EQ(box.vertex_count(), 8u);
  const Mesh once = subdivide(box, /*smooth=*/false);
  EXPECT_EQ(once.vertex_count(), 8u + 18u);  // V + E of the triangulated cube
  EXPECT_EQ(once.triangle_count(), 4 * box.triangle_count());
  for (const Vec3& p : once.positions) EXPECT_LT(box_distance(p, h), 1e-6) << p.x;
  EXPECT_NEAR(signed_volume(once), signed_volume(box), 1e-6);

  // Resampling a coarse board up to a target subdivides first, then decimates back to the
  // target; with linear subdivision every vertex stays on the board.
  const Mesh board = resample_to_vertex_count(box, 150, 0.002, /*smooth=*/false);
  EXPECT_EQ(board.vertex_count(), 150u);
  for (const Vec3& p : board.positions) EXPECT_LT(box_distance(p, h), 1e-6);
  EXPECT_NEAR(signed_volume(board), signed_volume(box), 1e-6);
  // Loop's rules would round the board off: its corners move inwards.
  const Mesh smooth = resample_to_vertex_count(box, 150, 0.002, /*smooth=*/true);
  double worst = 0.0;
  for (const Vec3& p : smooth.positions) worst = std::max(worst, box_distance(p, h));
  EXPECT_GT(worst, 0.02);
}

// ---- scene files -----------------------------------------------------------------------------

TEST_F(MeshGroups, SceneSplitsOneModelIntoPartsByGroup) {
  const Scene s = load_scene(scene(R"(
[[part]]
name = "floor"
mesh = "MODEL"
groups = ["wood"]
btf = "checker"
normalize = true
[[part]]
name = "wall"
mesh = "MODEL"
groups = ["p*t"]
normalize = true
)"));
  ASSERT_EQ(s.mesh.triangle_part.size(), 6u);
  std::map<std::uint16_t, std::set<std::pair<float, float>>> seen;  // part -> (x, y)
  std::size_t floor_triangles = 0;
  for (std::size_t t = 0; t < s.mesh.triangle_count(); ++t) {
    floor_triangles += s.mesh.part_of(t) == 0;
    for (int c = 0; c < 3; ++c) {
      const Vec3 p = s.mesh.positions[s.mesh.indices[3 * t + static_cast<std::size_t>(c)]];
      seen[s.mesh.part_of(t)].insert({p.x, p.y});
    }
  }
  EXPECT_EQ(floor_triangles, 4u);
  // Welded: the two floor squares share their middle edge (6 vertices, not 8); the wall has
  // its 4. The wall's bottom edge stays a separate copy per part.
  EXPECT_EQ(s.mesh.vertex_count(), 6u + 4u);
  // Normalised by the whole model's box (2 x 1 x 1, centred, on the ground), so the parts
  // stay where they were relative to each other: the floor spans x in [-0.5, 0.5] at y = 0,
  // the wall stands at x = 0.5 up to y = 0.5.
  for (const auto& [x, y] : seen[0]) {
    EXPECT_NEAR(y, 0.f, 1e-6f);
    EXPECT_GE(x, -0.5f - 1e-6f);
    EXPECT_LE(x, 0.5f + 1e-6f);
  }
  for (const auto& [x, y] : seen[1]) EXPECT_NEAR(x, 0.5f, 1e-6f);
  EXPECT_NEAR(s.mesh.bounds().hi.y, 0.5f, 1e-6f);
}

TEST_F(MeshGroups, SceneByObjectWithLinearSubdivisionToATarget) {
  const Scene s = load_scene(scene(R"(
[[part]]
name = "right"
mesh = "MODEL"
group_by = "object"
groups = ["right"]
uv_mapping = "planar"
target_vertices = 60
subdivision = "linear"
)"));
  EXPECT_EQ(s.mesh.vertex_count(), 60u);
  // The "right" object is flat pieces on y = 0 and x = 2: linear subdivision keeps them flat.
  for (const Vec3& p : s.mesh.positions)
    EXPECT_TRUE(std::abs(p.y) < 1e-6f || std::abs(p.x - 2.f) < 1e-6f) << p.x << " " << p.y;
}

TEST_F(MeshGroups, SceneErrorsNameThePartAndTheGroup) {
  expect_build_error("[[part]]\nname = \"p\"\nmesh = \"MODEL\"\ngroups = [\"stone\"]\n",
                     {"part 'p'", "no material group matching 'stone'", "wood, paint"});
  expect_build_error(
      "[[part]]\nname = \"p\"\nmesh = \"MODEL\"\ngroup_by = \"object\"\ngroups = [\"wood\"]\n",
      {"no object group matching 'wood'", "left, right"});
  expect_build_error(
      "[[part]]\nname = \"a\"\nmesh = \"MODEL\"\ngroups = [\"*\"]\n"
      "[[part]]\nname = \"b\"\nmesh = \"MODEL\"\ngroups = [\"paint\"]\n",
      {"part 'b'", "group 'paint'", "already belongs to part 'a'"});

  const auto parse_error = [&](const std::string& text, const std::string& needle) {
    const fs::path p = scene(text);
    try {
      parse_scene(p);
      FAIL() << "accepted:\n" << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  parse_error("[[part]]\nmesh = \"procedural:plane\"\ngroups = [\"wood\"]\n", "groups are for");
  parse_error("[[part]]\nmesh = \"MODEL\"\ngroup_by = \"object\"\n", "group_by needs groups");
  parse_error("[[part]]\nmesh = \"MODEL\"\ngroups = [\"wood\"]\ngroup_by = \"layer\"\n",
              "valid: material, object");
  parse_error("[[part]]\nmesh = \"MODEL\"\ngroups = []\n", "non-empty array");
  parse_error("[[part]]\nmesh = \"MODEL\"\ngroups = [3]\n", "non-empty strings");
  parse_error("[[part]]\nmesh = \"MODEL\"\nsubdivision = \"cubic\"\n", "valid: loop, linear");
}

}  // namespace
}  // namespace prt
