#include "prtlab/geometry/camera.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "prtlab/base/error.h"
#include "prtlab/geometry/procedural_shapes.h"
#include "prtlab/geometry/scene.h"
#include "support/temp_dir.h"

namespace prt {
namespace {
namespace fs = std::filesystem;

Camera oblique_camera() {
  Camera c;
  c.eye = {1.5, 2.0, 3.5};
  c.target = {-0.25, 0.5, 0.1};
  c.up = {0.1, 1.0, 0.2};  // not orthogonal to the view direction on purpose
  c.fov_y_deg = 35;
  c.width = 320;
  c.height = 200;
  return c;
}

TEST(Camera, CentreRayPointsAtTarget) {
  const Camera c = oblique_camera();
  const Vec3d d = c.ray_direction(0.5 * c.width, 0.5 * c.height);
  const Vec3d want = glm::normalize(c.target - c.eye);
  EXPECT_NEAR(glm::length(d - want), 0.0, 1e-12);
  // The centre of the middle pixel of an odd-sized image is the image centre.
  Camera odd = c;
  odd.width = 101;
  odd.height = 75;
  EXPECT_NEAR(glm::length(odd.pixel_direction(50, 37) - want), 0.0, 1e-12);
}

TEST(Camera, TopLeftCornerAndPixelZero) {
  Camera c;
  c.eye = {0, 0, 5};
  c.target = {0, 0, 0};
  c.up = {0, 1, 0};
  c.fov_y_deg = 60;
  c.width = 400;
  c.height = 200;
  // The image corner (0, 0) is up (+y) and to the left (-x) for a camera looking down -z.
  const double ty = std::tan(kPi / 6), tx = ty * 2.0;
  const Vec3d corner = glm::normalize(Vec3d(-tx, ty, -1.0));
  EXPECT_NEAR(glm::length(c.ray_direction(0, 0) - corner), 0.0, 1e-12);
  // Pixel (0, 0) is the top-left pixel: its centre is half a pixel inside that corner.
  const Vec3d p00 = c.pixel_direction(0, 0);
  EXPECT_LT(p00.x, 0.0);
  EXPECT_GT(p00.y, 0.0);
  const double half_pixel = 2.0 * ty / c.height * 0.5;
  EXPECT_NEAR(p00.x / -p00.z, -tx + half_pixel, 1e-12);
  EXPECT_NEAR(p00.y / -p00.z, ty - half_pixel, 1e-12);
  // Bottom-right pixel mirrors it.
  const Vec3d pbr = c.pixel_direction(c.width - 1, c.height - 1);
  EXPECT_NEAR(pbr.x, -p00.x, 1e-12);
  EXPECT_NEAR(pbr.y, -p00.y, 1e-12);
}

TEST(Camera, ProjectInvertsRayDirection) {
  const Camera c = oblique_camera();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> px(0.0, c.width), py(0.0, c.height), t(0.5, 20.0);
  for (int i = 0; i < 200; ++i) {
    const double x = px(rng), y = py(rng);
    const Vec3d p = c.eye + t(rng) * c.ray_direction(x, y);
    const auto q = c.project(p);
    ASSERT_TRUE(q.has_value());
    EXPECT_NEAR(q->x, x, 1e-8);
    EXPECT_NEAR(q->y, y, 1e-8);
  }
  EXPECT_FALSE(c.project(c.eye - (c.target - c.eye)).has_value());  // behind the eye
}

TEST(Camera, BasisIsRightHandedAndOrthonormal) {
  const CameraBasis b = oblique_camera().basis();
  EXPECT_NEAR(glm::length(b.forward), 1.0, 1e-12);
  EXPECT_NEAR(glm::length(b.right), 1.0, 1e-12);
  EXPECT_NEAR(glm::length(b.up), 1.0, 1e-12);
  EXPECT_NEAR(glm::dot(b.forward, b.right), 0.0, 1e-12);
  EXPECT_NEAR(glm::dot(b.forward, b.up), 0.0, 1e-12);
  // (right, up, -forward) is right-handed: right x up = -forward.
  EXPECT_NEAR(glm::length(glm::cross(b.right, b.up) + b.forward), 0.0, 1e-12);
  EXPECT_GT(b.up.y, 0.9);  // the up hint's roll is kept
}

TEST(Camera, InvalidCamerasThrow) {
  Camera c;
  c.fov_y_deg = 0;
  EXPECT_THROW(c.validate(), ParameterError);
  c = Camera{};
  c.target = c.eye;
  EXPECT_THROW(c.validate(), ParameterError);
  c = Camera{};
  c.up = c.target - c.eye;
  EXPECT_THROW(c.validate(), ParameterError);
  c = Camera{};
  c.width = 0;
  EXPECT_THROW(c.validate(), ParameterError);
  c = Camera{};
  c.eye.x = std::nan("");
  EXPECT_THROW(c.validate(), ParameterError);
  EXPECT_NO_THROW(Camera{}.validate());
}

// A framed view fits the vertices into `fill` of the image and centres them.
TEST(ViewPreset, FramedViewFillsAndCentres) {
  Mesh m = make_torus(0.8, 0.25, 48, 24);
  for (auto& p : m.positions) p = Vec3(p.x * 1.5f + 0.3f, p.y + 2.0f, p.z - 1.0f);
  ViewPreset v;
  v.name = "t";
  v.from = Vec3d(0.4, 0.7, 1.0);
  v.fill = 0.8;
  for (auto [w, h] : {std::pair{640, 480}, std::pair{300, 500}}) {
    const Camera c = resolve_view(v, m.positions, w, h);
    EXPECT_EQ(c.width, w);
    EXPECT_EQ(c.height, h);
    // The camera looks along -from.
    EXPECT_NEAR(glm::length(glm::normalize(c.eye - c.target) - glm::normalize(*v.from)), 0.0, 1e-9);
    Vec2d lo(1e30), hi(-1e30);
    for (const Vec3& p : m.positions) {
      const auto q = c.project(Vec3d(p));
      ASSERT_TRUE(q.has_value());
      lo = glm::min(lo, *q);
      hi = glm::max(hi, *q);
    }
    // Inside the image, centred to a pixel, and the tighter side spans fill of the image.
    EXPECT_GE(lo.x, 0.0);
    EXPECT_GE(lo.y, 0.0);
    EXPECT_LE(hi.x, w);
    EXPECT_LE(hi.y, h);
    EXPECT_NEAR(0.5 * (lo.x + hi.x), 0.5 * w, 1.0);
    EXPECT_NEAR(0.5 * (lo.y + hi.y), 0.5 * h, 1.0);
    const double span = std::max((hi.x - lo.x) / w, (hi.y - lo.y) / h);
    EXPECT_NEAR(span, v.fill, 0.01) << w << "x" << h;
  }
}

TEST(ViewPreset, ExplicitViewAndDefaults) {
  const std::vector<Vec3> pts = {Vec3(-1, 0, -1), Vec3(3, 2, 1)};
  ViewPreset v;
  v.name = "e";
  v.eye = Vec3d(5, 5, 5);
  v.fov_y_deg = 25;
  Camera c = resolve_view(v, pts, 64, 48);
  EXPECT_EQ(c.eye, Vec3d(5, 5, 5));
  EXPECT_EQ(c.target, Vec3d(1, 1, 0));  // the bounding-box centre
  EXPECT_EQ(c.fov_y_deg, 25);
  v.target = Vec3d(0, 1, 0);
  c = resolve_view(v, {}, 64, 48);  // explicit eye and target need no points
  EXPECT_EQ(c.target, Vec3d(0, 1, 0));

  ViewPreset bad = v;
  bad.from = Vec3d(0, 0, 1);  // both eye and from
  EXPECT_THROW(bad.validate(), ParameterError);
  bad = ViewPreset{};
  bad.name = "up";
  bad.from = Vec3d(0, 2, 0);  // parallel to up
  EXPECT_THROW(bad.validate(), ParameterError);
  bad.from = Vec3d(0, 0, 1);
  bad.fill = 1.5;
  EXPECT_THROW(bad.validate(), ParameterError);
  EXPECT_NO_THROW(automatic_view().validate());
}

TEST(CameraOptions, ParseHelpers) {
  EXPECT_EQ(parse_vec3("1,2.5,-3", "--eye"), Vec3d(1, 2.5, -3));
  EXPECT_EQ(parse_vec3(" 1 , +2 ,3e-1 ", "--eye"), Vec3d(1, 2, 0.3));
  for (const char* bad : {"1,2", "1,2,3,4", "a,b,c", "1,,3", "", "1,2,inf", "1;2;3"}) {
    try {
      parse_vec3(bad, "--target");
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const ParameterError& e) {
      EXPECT_NE(std::string(e.what()).find("--target"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(parse_resolution("640x480", "--size"), std::make_pair(640, 480));
  EXPECT_THROW(parse_resolution("640*480", "--size"), ParameterError);
  EXPECT_THROW(parse_resolution("0x480", "--size"), ParameterError);
  EXPECT_THROW(parse_resolution("64x", "--size"), ParameterError);
  EXPECT_EQ(parse_number("42.5", "--fov"), 42.5);
  EXPECT_THROW(parse_number("wide", "--fov"), ParameterError);

  const CameraOverrides o = parse_camera_overrides("0,1,4", "", "30", "200x100");
  ASSERT_TRUE(o.eye && o.fov_y_deg && o.width && o.height);
  EXPECT_FALSE(o.target.has_value());
  const Camera c = apply_overrides(Camera{}, o);
  EXPECT_EQ(c.eye, Vec3d(0, 1, 4));
  EXPECT_EQ(c.target, Camera{}.target);
  EXPECT_EQ(c.fov_y_deg, 30);
  EXPECT_EQ(c.width, 200);
  EXPECT_TRUE(parse_camera_overrides("", "", "").empty());
  EXPECT_THROW(apply_overrides(Camera{}, parse_camera_overrides("", "", "190")), ParameterError);
}

// ---- view presets in scene files ------------------------------------------------------------

class SceneViews : public ::testing::Test {
 protected:
  fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }
  void expect_error(const std::string& views, const std::string& needle) {
    // Views first: a root key such as `view = 3` must come before the first table header.
    const fs::path p = write("bad_view.toml", views + kPart);
    try {
      parse_scene(p);
      FAIL() << "accepted:\n" << views;
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(p.string()), std::string::npos) << msg;
      EXPECT_NE(msg.find(needle), std::string::npos) << "expected '" << needle << "' in: " << msg;
    }
  }
  static constexpr const char* kPart =
      "[[part]]\nmesh = \"procedural:sphere\"\nparams = { radius = 0.5, segments = 16, rings = 8 "
      "}\n";
  prt::testing::TempDir tmp_{"camera_test"};
  fs::path dir_ = tmp_.path();
};

TEST_F(SceneViews, ParseAndSelect) {
  const fs::path p = write("views.toml", std::string(kPart) + R"(
[[view]]
name = "front"
from = [0, 0.3, 1]
fov = 30
fill = 0.75

[[view]]
name = "close"
eye = [0.5, 0.6, 1.2]
target = [0, 0.1, 0]
up = [0, 0, 1]
)");
  const SceneDesc d = parse_scene(p);
  ASSERT_EQ(d.views.size(), 2u);
  EXPECT_EQ(d.views[0].name, "front");
  EXPECT_EQ(*d.views[0].from, Vec3d(0, 0.3, 1));
  EXPECT_FALSE(d.views[0].eye.has_value());
  EXPECT_EQ(d.views[0].fov_y_deg, 30);
  EXPECT_EQ(d.views[0].fill, 0.75);
  EXPECT_EQ(*d.views[1].eye, Vec3d(0.5, 0.6, 1.2));
  EXPECT_EQ(*d.views[1].target, Vec3d(0, 0.1, 0));
  EXPECT_EQ(d.views[1].up, Vec3d(0, 0, 1));

  EXPECT_EQ(scene_view(d, "").name, "front");  // the first preset is the default
  EXPECT_EQ(scene_view(d, "close").name, "close");
  try {
    scene_view(d, "top");
    FAIL();
  } catch (const ParameterError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("views.toml"), std::string::npos) << msg;
    EXPECT_NE(msg.find("front, close"), std::string::npos) << msg;
  }

  const Scene s = build_scene(d);
  CameraOverrides o;
  o.width = 200;
  o.height = 100;
  o.fov_y_deg = 50;
  const Camera c = scene_camera(s, "close", o);
  EXPECT_EQ(c.eye, Vec3d(0.5, 0.6, 1.2));
  EXPECT_EQ(c.width, 200);
  EXPECT_EQ(c.fov_y_deg, 50);

  // Without presets the automatic view frames the scene.
  const Scene bare = load_scene(write("bare.toml", kPart));
  EXPECT_TRUE(bare.desc.views.empty());
  const Camera a = scene_camera(bare, "");
  EXPECT_EQ(a.width, 640);
  EXPECT_EQ(a.height, 480);
  EXPECT_GT(a.eye.z, 1.0);
}

TEST_F(SceneViews, BadPresetsNameTheFile) {
  expect_error("[[view]]\nfrom = [0, 0, 1]\n", "missing required key 'name'");
  expect_error("[[view]]\nname = \"a\"\nfrom = [0, 0, 1]\nzoom = 2\n", "unknown key 'zoom'");
  expect_error("[[view]]\nname = \"a\"\n", "exactly one of 'eye'");
  expect_error("[[view]]\nname = \"a\"\nfrom = [0, 0, 1]\neye = [1, 1, 1]\n", "exactly one");
  expect_error("[[view]]\nname = \"a\"\nfrom = [0, 1, 0]\n", "parallel");
  expect_error("[[view]]\nname = \"a\"\nfrom = [0, 0]\n", "array of 3");
  expect_error("[[view]]\nname = \"a\"\nfrom = [0, 0, 1]\nfov = 180\n", "fov");
  expect_error("[[view]]\nname = \"a\"\nfrom = [0, 0, 1]\nfov = \"wide\"\n", "wrong type");
  expect_error(
      "[[view]]\nname = \"a\"\nfrom = [0, 0, 1]\n[[view]]\nname = \"a\"\neye = [0, 0, 3]\n",
      "defined twice");
  expect_error("view = 3\n", "array of tables");
}

// Every committed scene has a "front" preset first and at least one more.
TEST(CommittedScenes, HaveViewPresets) {
  int scenes = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(PRTLAB_SOURCE_DIR) / "scenes")) {
    if (entry.path().extension() != ".toml") continue;
    ++scenes;
    const SceneDesc d = parse_scene(entry.path());
    ASSERT_GE(d.views.size(), 2u) << entry.path();
    EXPECT_EQ(d.views.front().name, "front") << entry.path();
  }
  EXPECT_GE(scenes, 6);
}

}  // namespace
}  // namespace prt
