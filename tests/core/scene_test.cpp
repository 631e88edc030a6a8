#include "prtlab/geometry/scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>

#include "prtlab/base/error.h"
#include "prtlab/btf/scene_btfs.h"
#include "prtlab/geometry/mesh_io.h"
#include "prtlab/geometry/procedural_shapes.h"
#include "prtlab/storage/data_paths.h"
#include "support/temp_dir.h"

namespace prt {
namespace {
namespace fs = std::filesystem;

class SceneFile : public ::testing::Test {
 protected:
  fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }
  // Parsing must fail with an InputError naming the file and containing `needle`.
  void expect_error(const std::string& text, const std::string& needle) {
    const fs::path p = write("bad.toml", text);
    try {
      parse_scene(p);
      FAIL() << "accepted:\n" << text;
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(p.string()), std::string::npos) << msg;
      EXPECT_NE(msg.find(needle), std::string::npos) << "expected '" << needle << "' in: " << msg;
    }
  }
  prt::testing::TempDir tmp_{"scene_test"};
  fs::path dir_ = tmp_.path();
};

constexpr const char* kValid = R"(
name = "t"
local_grid = 4
cubemap_resolution = 8
supersampling = 3
[[part]]
name = "ground"
mesh = "procedural:plane"
params = { size_x = 2.0, size_z = 2.0, n = 4 }
[[part]]
name = "balls"
mesh = "procedural:sphere"
btf = "bumps"
params = { radius = 0.25, segments = 8, rings = 4 }
[[part.instance]]
translate = [0.5, 0.5, 0.0]
[[part.instance]]
translate = [-0.5, 0.5, 0.0]
scale = [2.0, 2.0, 2.0]
)";

TEST_F(SceneFile, ParsesAndBuildsWithInstances) {
  const Scene s = load_scene(write("ok.toml", kValid));
  EXPECT_EQ(s.desc.local_grid, 4);
  EXPECT_EQ(s.desc.cubemap_resolution, 8);
  EXPECT_EQ(s.desc.supersampling, 3);
  ASSERT_EQ(s.desc.parts.size(), 2u);
  const std::size_t plane_verts = 25;              // (n + 1)^2
  const std::size_t sphere_verts = 9 * 3 + 2 * 8;  // (segments + 1)(rings - 1) + 2 segments
  EXPECT_EQ(s.mesh.vertex_count(), plane_verts + 2 * sphere_verts);
  ASSERT_EQ(s.mesh.triangle_part.size(), s.mesh.triangle_count());
  // The second instance is scaled 2x about the origin, then moved: its top reaches 0.5 + 0.5.
  const Aabb b = s.mesh.bounds();
  EXPECT_NEAR(b.hi.y, 1.0, 1e-5);
  EXPECT_NEAR(b.lo.x, -1.0, 1e-5);
  ASSERT_EQ(s.mesh.normals.size(), s.mesh.vertex_count());
  for (const auto& n : s.mesh.normals) EXPECT_NEAR(glm::length(n), 1.0f, 1e-4f);
}

TEST_F(SceneFile, ErrorsNameFileAndProblem) {
  expect_error("nmae = \"x\"\n[[part]]\nmesh = \"procedural:plane\"\n", "unknown key 'nmae'");
  expect_error("name = \"x\"\n", "no [[part]]");
  expect_error("[[part]]\nname = \"p\"\n", "missing required key 'mesh'");
  expect_error("local_grid = 0\n[[part]]\nmesh = \"procedural:plane\"\n", "out of range");
  expect_error("local_grid = \"eight\"\n[[part]]\nmesh = \"procedural:plane\"\n", "wrong type");
  expect_error("[[part]]\nmesh = \"procedural:plane\"\ntransform = { scale = [1, 2] }\n",
               "array of 3");
  expect_error("[[part]]\nmesh = \"procedural:plane\"\ncolour = 3\n", "unknown key 'colour'");
  expect_error("this is not toml ===", "line 1");
  expect_error(
      "target_vertices = 100\n[[part]]\nmesh = \"procedural:plane\"\n[[part]]\nmesh = "
      "\"procedural:plane\"\n",
      "exactly one part");
}

TEST_F(SceneFile, ProceduralShapeErrorsAtBuild) {
  auto build_error = [&](const std::string& text, const std::string& needle) {
    const fs::path p = write("bad_build.toml", text);
    try {
      load_scene(p);
      FAIL() << "built:\n" << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  build_error("[[part]]\nmesh = \"procedural:cone\"\n", "unknown procedural shape 'cone'");
  build_error("[[part]]\nmesh = \"procedural:sphere\"\nparams = { radius = 1.0, sgements = 8 }\n",
              "unknown parameter 'sgements'");
  build_error("[[part]]\nmesh = \"procedural:sphere\"\nparams = { radius = -1.0 }\n",
              "positive length");
  build_error("[[part]]\nmesh = \"procedural:plane\"\nparams = { n = 2.5 }\n", "integer");
  build_error("[[part]]\nmesh = \"no_such_mesh.off\"\n", "no_such_mesh.off");
}

TEST_F(SceneFile, MissingFileIsNamed) {
  try {
    parse_scene(dir_ / "nope.toml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("nope.toml"), std::string::npos);
  }
}

TEST_F(SceneFile, OutOfRangeAndNonFiniteValuesAreRefusedWhereWritten) {
  expect_error("[[part]]\nmesh = \"procedural:plane\"\ntarget_vertices = 99999999999\n",
               "too large");
  expect_error("target_vertices = 99999999999\n[[part]]\nmesh = \"procedural:plane\"\n",
               "too large");
  expect_error("[[part]]\nmesh = \"procedural:plane\"\ntransform = { scale = [1, 0, 1] }\n",
               "singular");
  expect_error(
      "[[part]]\nmesh = \"procedural:plane\"\ntransform = { scale = [1e200, 1e200, "
      "1e200] }\n",
      "singular");
  expect_error("[[part]]\nmesh = \"procedural:plane\"\n[[part.instance]]\nscale = [0, 1, 1]\n",
               "singular");
  expect_error("[[part]]\nmesh = \"procedural:plane\"\ntransform = { translate = [nan, 0, 0] }\n",
               "finite");
  expect_error("[[part]]\nmesh = \"procedural:plane\"\ntransform = { rotate_deg = [0, inf, 0] }\n",
               "finite");
}

TEST_F(SceneFile, AnUnknownBtfNamesTheSceneFile) {
  const fs::path p = write("btf.toml", "[[part]]\nmesh = \"procedural:plane\"\nbtf = \"wevae\"\n");
  try {
    check_scene_btf_names(parse_scene(p));
    FAIL() << "an unknown BTF was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("wevae"), std::string::npos) << e.what();
  }
  // A file next to the scene is a BTF file, read from the scene's folder.
  std::ofstream(dir_ / "mine.btf") << "x";
  check_scene_btf_names(parse_scene(write("ok.toml",
                                          "[[part]]\nmesh = \"procedural:plane\"\n"
                                          "btf = \"mine.btf\"\n")));
}

// A scene's mesh names resolve against the data cache and the scene file's folder, never the
// working directory: a stray file there must not replace the mesh.
class SceneMeshPaths : public SceneFile {
 protected:
  void SetUp() override {
    if (const char* d = std::getenv("PRTLAB_DATA")) saved_data_ = d;
    saved_cwd_ = fs::current_path();
    data_ = dir_ / "data";
    scene_dir_ = dir_ / "scenes";
    cwd_ = dir_ / "cwd";
    for (const auto& d : {data_ / "meshes", scene_dir_ / "sub", cwd_}) fs::create_directories(d);
    ::setenv("PRTLAB_DATA", data_.c_str(), 1);
    fs::current_path(cwd_);
    scene_ = scene_dir_ / "s.toml";
    std::ofstream(scene_) << "[[part]]\nmesh = \"m.obj\"\n";
  }
  void TearDown() override {
    fs::current_path(saved_cwd_);
    if (saved_data_)
      ::setenv("PRTLAB_DATA", saved_data_->c_str(), 1);
    else
      ::unsetenv("PRTLAB_DATA");
  }
  // A mesh whose triangle count tells which file was read.
  static void put_mesh(const fs::path& p, int segments) {
    save_mesh_obj(make_sphere(1.0, segments, segments / 2), p);
  }
  std::optional<std::string> saved_data_;
  fs::path saved_cwd_, data_, scene_dir_, cwd_, scene_;
};

TEST_F(SceneMeshPaths, ABareNameIsTheDataCacheMeshEvenWithAStrayFileInTheWorkingDirectory) {
  put_mesh(data_ / "meshes" / "m.obj", 8);
  put_mesh(cwd_ / "m.obj", 16);
  EXPECT_EQ(fs::canonical(resolve_mesh("m.obj", scene_)),
            fs::canonical(data_ / "meshes" / "m.obj"));
  const Scene a = load_scene(scene_);
  const Mesh cached = load_mesh(data_ / "meshes" / "m.obj");
  EXPECT_EQ(a.mesh.triangle_count(), cached.triangle_count());
}

TEST_F(SceneMeshPaths, ABareNameNotInTheCacheIsTheFileNextToTheScene) {
  put_mesh(scene_dir_ / "m.obj", 8);
  put_mesh(cwd_ / "m.obj", 16);
  EXPECT_EQ(fs::canonical(resolve_mesh("m.obj", scene_)), fs::canonical(scene_dir_ / "m.obj"));
}

TEST_F(SceneMeshPaths, RelativePathsAreReadFromTheSceneFilesFolder) {
  put_mesh(scene_dir_ / "sub" / "m.obj", 8);
  fs::create_directories(cwd_ / "sub");
  put_mesh(cwd_ / "sub" / "m.obj", 16);
  EXPECT_EQ(fs::canonical(resolve_mesh("sub/m.obj", scene_)),
            fs::canonical(scene_dir_ / "sub" / "m.obj"));
  EXPECT_EQ(fs::canonical(resolve_mesh("./sub/m.obj", scene_)),
            fs::canonical(scene_dir_ / "sub" / "m.obj"));
}

TEST_F(SceneMeshPaths, AMeshOnlyInTheWorkingDirectoryIsNotFoundAndTheErrorNamesTheScene) {
  put_mesh(cwd_ / "m.obj", 16);
  for (const std::string name : {"m.obj", "./m.obj"}) {
    try {
      (void)resolve_mesh(name, scene_);
      FAIL() << name << " was found in the working directory";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(scene_.string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}

// The committed scene files build and hit the vertex counts of the papers' scenes.
TEST(PaperScenes, VertexCounts) {
  struct Case {
    const char* scene;
    std::size_t paper_vertices;
    const char* data_mesh;  ///< the data-cache mesh the scene needs, or nullptr
  };
  const Case cases[] = {
      {"tiny-sphere-plane", 320, nullptr},       {"chair-procedural", 16101, nullptr},
      {"temple-procedural", 32409, nullptr},     {"chair", 16101, "oakChair.obj"},
      {"temple", 32409, "samurai_monastry.obj"}, {"bunny", 3286, "bunny00.off"},
      {"armor", 10652, "armadillo.off"}};
  for (const auto& c : cases) {
    if (c.data_mesh && !fs::exists(data_dir() / "meshes" / c.data_mesh)) {
      std::printf("skipping %s: data cache missing (run scripts/setup.sh --data)\n", c.scene);
      continue;
    }
    const Scene s =
        load_scene(fs::path(PRTLAB_SOURCE_DIR) / "scenes" / (std::string(c.scene) + ".toml"));
    const double rel = std::abs(double(s.mesh.vertex_count()) - double(c.paper_vertices)) /
                       double(c.paper_vertices);
    EXPECT_LT(rel, 0.005) << c.scene << ": " << s.mesh.vertex_count() << " vertices vs "
                          << c.paper_vertices;
  }
}

}  // namespace
}  // namespace prt
