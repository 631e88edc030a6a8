// The frame loop: a view-only change traces a new G-buffer and reuses L* (no relight) and gives
// the image of a fresh render with the same inputs; a light change relights and gives the
// fresh render's image too; the OpenCL and C++ paths agree. Also the environment rotation and
// camera orbit helpers of the fps command.
#include "prtlab/render/frame_renderer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "prtlab/btf/btf_materials.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/transfer/radiance_to_bins.h"
#include "prtlab/transfer/transfer_matrix.h"
#include "support/tiny_frame_scene.h"

namespace prt {
namespace {

double max_error_vs_image_max(const RgbImage& a, const RgbImage& b) {
  EXPECT_EQ(a.pixels.size(), b.pixels.size());
  double err = 0.0, peak = 0.0;
  for (std::size_t i = 0; i < std::min(a.pixels.size(), b.pixels.size()); ++i)
    for (int c = 0; c < 3; ++c) {
      err = std::max(err, static_cast<double>(std::abs(a.pixels[i][c] - b.pixels[i][c])));
      peak = std::max(peak, static_cast<double>(std::abs(b.pixels[i][c])));
    }
  return peak > 0.0 ? err / peak : err;
}

struct Fixture {
  const testing::TinyFrameScene& tiny = testing::tiny_frame_scene();
  const Scene& scene = tiny.scene;
  std::shared_ptr<const CompressedTransfer> transfer = tiny.compress("uncompressed");
  // Relights into SH of order 4: 16 coefficients for M = 16 cells, so nothing is lost, but
  // every frame goes through the conversion to the bins.
  std::shared_ptr<const CompressedTransfer> sh_transfer =
      tiny.compress("sh_probe", {{"order", "4"}});
  const ShadingMaterials& materials = tiny.materials;
  Camera front, top;
  const Cubemap& sky = tiny.sky;
  const Cubemap& sky2 = tiny.sky2;

  Fixture() {
    CameraOverrides size;
    size.width = 80;
    size.height = 60;
    front = scene_camera(scene, "front", size);
    top = scene_camera(scene, "top", size);
  }

  FrameRenderer renderer(bool device) const {
    return FrameRenderer(scene.mesh, materials, transfer, device ? default_context() : nullptr);
  }
  RgbImage fresh(bool device, const Camera& cam, const Cubemap& env) const {
    FrameRenderer r = renderer(device);
    r.set_camera(cam);
    r.set_environment(env);
    r.render();
    return r.image();
  }
};

const Fixture& fixture() {
  static const Fixture f;
  return f;
}

class FrameLoop : public ::testing::TestWithParam<bool> {
 protected:
  void SetUp() override {
    if (GetParam() && !default_context()) GTEST_SKIP() << "no OpenCL device";
  }
  bool device() const { return GetParam(); }
};

TEST_P(FrameLoop, ViewChangeReusesRadianceAndMatchesAFreshRender) {
  const auto& f = fixture();
  FrameRenderer r = f.renderer(device());
  // Unculled: the light reached every vertex, so no view change relights. (Culled, a view change
  // relights the newly visible vertices: tests/core/frame_culling_test.cpp.)
  r.set_culling(false);
  EXPECT_EQ(r.uses_opencl(), device());
  r.set_camera(f.front);
  r.set_environment(f.sky);
  FrameStats first = r.render();
  EXPECT_EQ(first.counters.relights, 1u);
  EXPECT_EQ(first.counters.gbuffer_traces, 1u);
  const RgbImage front_image = r.image();

  r.set_camera(f.top);
  const FrameStats second = r.render();
  EXPECT_EQ(second.counters.relights, 1u) << "a view-only change must not relight";
  EXPECT_EQ(second.counters.gbuffer_traces, 2u);
  EXPECT_EQ(second.counters.frames, 2u);
  EXPECT_EQ(second.times.project_ms, 0.0);
  EXPECT_EQ(second.times.relight_ms, 0.0);
  EXPECT_EQ(second.times.upload_ms, 0.0);
  EXPECT_EQ(second.relit_vertices, 0u);
  const RgbImage top_image = r.image();
  EXPECT_LE(max_error_vs_image_max(top_image, f.fresh(device(), f.top, f.sky)), 1e-6);
  EXPECT_GT(max_error_vs_image_max(top_image, front_image), 0.05) << "the view did change";
}

TEST_P(FrameLoop, LightChangeRelightsAndMatchesAFreshRender) {
  const auto& f = fixture();
  FrameRenderer r = f.renderer(device());
  r.set_camera(f.front);
  r.set_environment(f.sky);
  r.render();
  const RgbImage before = r.image();
  r.set_environment(f.sky2);
  const FrameStats stats = r.render();
  EXPECT_EQ(stats.counters.relights, 2u);
  EXPECT_EQ(stats.counters.gbuffer_traces, 1u) << "a light change must not retrace";
  EXPECT_EQ(stats.times.gbuffer_ms, 0.0);
  const RgbImage after = r.image();
  EXPECT_LE(max_error_vs_image_max(after, f.fresh(device(), f.front, f.sky2)), 1e-6);
  EXPECT_GT(max_error_vs_image_max(after, before), 0.05) << "the light did change";
}

// A backend whose relight is SH renders, on both paths, the image of the independent
// composition: its C++ relight, to_pixel_basis, the reference shader. The first light change
// sizes the device converter, the second takes its steady path.
TEST_P(FrameLoop, AnShOutputBackendRendersThroughTheBins) {
  const auto& f = fixture();
  ASSERT_EQ(f.sh_transfer->output_basis(), RadianceBasis::kSphericalHarmonics);
  FrameRenderer r(f.scene.mesh, f.materials, f.sh_transfer, device() ? default_context() : nullptr);
  r.set_camera(f.front);
  for (const Cubemap* env : {&f.sky, &f.sky2}) {
    r.set_environment(*env);
    r.render();
    LocalRadiance sh;
    f.sh_transfer->relight(f.sh_transfer->project_light(*env), sh);
    const LocalRadiance pixel = to_pixel_basis(sh, HemisphereGrid(f.scene.desc.local_grid));
    const RgbImage expected =
        shade_frame_reference(r.gbuffer(), f.scene.mesh, f.materials, pixel, env);
    EXPECT_LT(max_error_vs_image_max(r.image(), expected), 1e-4);
    EXPECT_EQ(r.radiance().basis, RadianceBasis::kPixel);
    EXPECT_LT(relative_l2_error(r.radiance(), pixel), 1e-5);
  }
}

INSTANTIATE_TEST_SUITE_P(Paths, FrameLoop, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& i) {
                           return i.param ? std::string("OpenCL") : std::string("Cpp");
                         });

TEST(FrameRenderer, OpenClAndCppPathsAgree) {
  if (!default_context()) GTEST_SKIP() << "no OpenCL device";
  const auto& f = fixture();
  EXPECT_LE(max_error_vs_image_max(f.fresh(true, f.front, f.sky), f.fresh(false, f.front, f.sky)),
            1e-5);
}

TEST(FrameRenderer, RenderNeedsCameraAndEnvironment) {
  const auto& f = fixture();
  FrameRenderer r = f.renderer(false);
  EXPECT_THROW(r.render(), ParameterError);
  r.set_camera(f.front);
  EXPECT_THROW(r.render(), ParameterError);
  EXPECT_THROW(r.image(), ParameterError);
}

TEST(FrameRenderer, RotatedEnvironmentKeepsPowerAndTurnsAboutY) {
  LatLongImage img;
  img.width = 16;
  img.height = 8;
  img.texels.assign(16 * 8, Rgb(0.0f));
  // One bright column whose centre looks down phi = 2 pi (4 + 0.5) / 16.
  for (int row = 0; row < 8; ++row) img.texels[row * 16 + 4] = Rgb(1.0f, 2.0f, 3.0f);
  const LatLongImage rotated = rotate_latlong_y(img, 45.0);  // 2 columns
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(rotated.total_power()[c], img.total_power()[c], 1e-9);
  // Rotating by +45 deg (+x towards -z) maps phi to phi - pi/4: column 4 moves to column 2.
  EXPECT_EQ(rotated.at(2, 3), Rgb(1.0f, 2.0f, 3.0f));
  EXPECT_EQ(rotated.at(4, 3), Rgb(0.0f));
  const Vec3d before = latlong_direction(4.5 / 16, 0.5), after = latlong_direction(2.5 / 16, 0.5);
  const double a = kPi / 4;
  EXPECT_NEAR(after.x, before.x * std::cos(a) + before.z * std::sin(a), 1e-12);
  EXPECT_NEAR(after.z, -before.x * std::sin(a) + before.z * std::cos(a), 1e-12);
  // Half a column: the average of the two neighbours.
  const LatLongImage half = rotate_latlong_y(img, 360.0 / 32);
  EXPECT_EQ(half.at(3, 0), Rgb(0.5f, 1.0f, 1.5f));
  EXPECT_EQ(half.at(4, 0), Rgb(0.5f, 1.0f, 1.5f));
}

TEST(FrameRenderer, OrbitKeepsDistanceAndTarget) {
  Camera c;
  c.eye = {1, 2, 3};
  c.target = {0.5, 0, 0};
  const Camera o = orbit_camera(c, 90.0);
  EXPECT_NEAR(glm::length(o.eye - o.target), glm::length(c.eye - c.target), 1e-12);
  EXPECT_NEAR(o.eye.y, 2.0, 1e-12);
  const Camera full = orbit_camera(c, 360.0);
  EXPECT_NEAR(glm::length(full.eye - c.eye), 0.0, 1e-12);
}

}  // namespace
}  // namespace prt
