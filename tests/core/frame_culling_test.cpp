// Culling in the frame loop (docs/rendering.md, "Culling"): with culling on, a light change
// relights only the vertices of the hit triangles, and a view change relights the newly
// visible ones. Over a sequence of camera and light changes (including a move that reveals
// vertices hidden at the last light change, and lights black on some cube faces) the image is
// bit-identical to the unculled renderer's, on the C++ and the OpenCL path, for `uncompressed`
// and `bicluster`. The visible set is checked against an independent scan of the G-buffer.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <set>

#include "prtlab/btf/btf_materials.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/render/frame_renderer.h"
#include "prtlab/render/visible_vertices.h"
#include "prtlab/transfer/transfer_matrix.h"
#include "support/tiny_frame_scene.h"

namespace prt {
namespace {

Cubemap black_faces(Cubemap c, std::initializer_list<int> faces) {
  const std::size_t per_face = c.radiance.size() / 6;
  for (const int f : faces) std::fill_n(c.radiance.begin() + f * per_face, per_face, Rgb(0.f));
  return c;
}

struct Fixture {
  const testing::TinyFrameScene& tiny = testing::tiny_frame_scene();
  const Scene& scene = tiny.scene;
  std::map<std::string, std::shared_ptr<const CompressedTransfer>> transfers;
  const ShadingMaterials& materials = tiny.materials;
  std::vector<Camera> cameras;  // front, top, from behind, a close-up
  const Cubemap& sky = tiny.sky;
  const Cubemap& sky2 = tiny.sky2;

  Fixture() {
    for (const char* b : {"uncompressed", "bicluster"}) transfers[b] = tiny.compress(b);
    CameraOverrides size;
    size.width = 64;
    size.height = 48;
    const Camera front = scene_camera(scene, "front", size);
    Camera close = front;
    close.eye = front.target + 0.35 * (front.eye - front.target);
    cameras = {front, scene_camera(scene, "top", size), orbit_camera(front, 180.0), close};
  }
};

const Fixture& fixture() {
  static const Fixture f;
  return f;
}

bool same_bits(const RgbImage& a, const RgbImage& b) {
  return a.pixels.size() == b.pixels.size() &&
         std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(Rgb)) == 0;
}

struct CullCase {
  std::string backend;
  bool device;
};

class FrameCulling : public ::testing::TestWithParam<CullCase> {
 protected:
  void SetUp() override {
    if (GetParam().device && !default_context()) GTEST_SKIP() << "no OpenCL device";
  }
  FrameRenderer renderer(bool cull) const {
    const auto& f = fixture();
    FrameRenderer r(f.scene.mesh, f.materials, f.transfers.at(GetParam().backend),
                    GetParam().device ? default_context() : nullptr);
    r.set_culling(cull);
    return r;
  }
};

TEST_P(FrameCulling, ImagesEqualTheUnculledOnesBitForBit) {
  const auto& f = fixture();
  FrameRenderer culled = renderer(true), full = renderer(false);
  ASSERT_TRUE(culled.culls()) << "both backends relight vertex subsets on both paths";
  ASSERT_FALSE(full.culls());
  const std::size_t vertices = f.scene.mesh.positions.size();
  const Cubemap half = black_faces(f.sky, {1, 3, 5});
  const Cubemap sun_side = black_faces(f.sky2, {0, 2, 4});
  // (camera index or -1, light or null): light changes, view changes, and a view change right
  // after a light change that reveals vertices hidden when the light was set.
  struct Step {
    int camera;
    const Cubemap* light;
  };
  const std::vector<Step> steps = {{0, &f.sky},  {-1, &f.sky2}, {2, nullptr}, {1, nullptr},
                                   {-1, &half},  {3, nullptr},  {0, nullptr}, {-1, &sun_side},
                                   {2, nullptr}, {3, &f.sky},   {1, nullptr}};
  std::uint64_t culled_relit = 0, revealed = 0;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    SCOPED_TRACE(::testing::Message() << "step " << i);
    for (FrameRenderer* r : {&culled, &full}) {
      if (steps[i].camera >= 0) r->set_camera(f.cameras[steps[i].camera]);
      if (steps[i].light) r->set_environment(*steps[i].light);
    }
    const FrameStats c = culled.render();
    const FrameStats u = full.render();
    EXPECT_TRUE(same_bits(culled.image(), full.image())) << "culled image differs";
    EXPECT_EQ(c.visible_vertices, culled.visible_vertices().size());
    if (steps[i].light) {
      EXPECT_EQ(u.relit_vertices, vertices);
    }
    if (steps[i].light && steps[i].camera < 0) {
      EXPECT_EQ(c.relit_vertices, c.visible_vertices);
    }
    if (!steps[i].light && c.relit_vertices > 0) ++revealed;
    culled_relit += c.relit_vertices;
  }
  EXPECT_LT(culled_relit, full.counters().relit_vertices) << "culling saved nothing";
  EXPECT_GT(revealed, 0u) << "no view change revealed a vertex the last light had not reached";
  EXPECT_EQ(culled.counters().relit_vertices, culled_relit);
}

TEST_P(FrameCulling, EveryVisibleVertexIsCurrentAfterAViewChange) {
  const auto& f = fixture();
  FrameRenderer culled = renderer(true), full = renderer(false);
  for (FrameRenderer* r : {&culled, &full}) {
    r->set_camera(f.cameras[0]);
    r->set_environment(f.sky);
    r->set_environment(f.sky2);
    r->set_camera(f.cameras[2]);  // the far side: hidden at both light changes
  }
  const LocalRadiance& a = culled.radiance();
  const LocalRadiance& b = full.radiance();
  ASSERT_EQ(a.values.size(), b.values.size());
  const std::size_t dim = static_cast<std::size_t>(a.dim);
  for (const std::uint32_t v : culled.visible_vertices())
    for (std::size_t j = 0; j < dim; ++j)
      ASSERT_EQ(std::memcmp(&a.values[v * dim + j], &b.values[v * dim + j], sizeof(Rgb)), 0)
          << "vertex " << v << " row " << j << " is stale";
}

INSTANTIATE_TEST_SUITE_P(Backends, FrameCulling,
                         ::testing::Values(CullCase{"uncompressed", false},
                                           CullCase{"uncompressed", true},
                                           CullCase{"bicluster", false},
                                           CullCase{"bicluster", true}),
                         [](const ::testing::TestParamInfo<CullCase>& i) {
                           return i.param.backend + (i.param.device ? "_OpenCL" : "_Cpp");
                         });

TEST(VisibleVertices, AreExactlyTheVerticesOfHitTriangles) {
  const auto& f = fixture();
  const GBufferTracer tracer(f.scene.mesh);
  for (const Camera& cam : f.cameras) {
    const GBuffer g = tracer.trace(cam);
    std::set<std::uint32_t> expected;
    for (int y = 0; y < g.height; ++y)
      for (int x = 0; x < g.width; ++x) {
        const std::int32_t t = g.triangle[g.index(x, y)];
        if (t < 0) continue;
        for (int c = 0; c < 3; ++c) expected.insert(f.scene.mesh.indices[3 * t + c]);
      }
    const std::vector<std::uint32_t> got = visible_vertices(g, f.scene.mesh);
    EXPECT_EQ(got, std::vector<std::uint32_t>(expected.begin(), expected.end()));
    EXPECT_GT(got.size(), 0u);
    EXPECT_LT(got.size(), f.scene.mesh.positions.size()) << "every vertex visible: no culling";
  }
  GBuffer bad = tracer.trace(f.cameras[0]);
  bad.triangle[0] = static_cast<std::int32_t>(f.scene.mesh.triangle_count());
  EXPECT_THROW(visible_vertices(bad, f.scene.mesh), ParameterError);
}

}  // namespace
}  // namespace prt
