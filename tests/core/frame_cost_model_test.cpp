// The frame cost model (render/frame_cost_model.h) against counts made by hand from the kernels
// (kernels/btf_shading.cl): per hit pixel and light-basis value and channel, L* interpolated
// from three vertices (w0 l0 + w1 l1 + w2 l2: 3 multiplies, 2 adds) and dotted with the
// material's value (a multiply, an add); and the model's time as the larger of its two bounds.
#include "prtlab/render/frame_cost_model.h"

#include <gtest/gtest.h>

namespace prt {
namespace {

FrameCounts counts() {
  FrameCounts c;
  c.pixels = 640 * 480;
  c.hits = 74308;
  c.vertices = 3286;
  c.visible_share = 0.5;
  c.light_values = 64;
  c.transfer_bytes = 1e6;
  c.transfer_flops = 2e7;
  c.material_flops_per_pixel = 1000;
  c.device_shading = true;
  c.view_cache_bytes = 3e6;
  c.cached_shade_bytes = 4e6;
  return c;
}

const StageCost& stage(const std::vector<StageCost>& stages, const std::string& name) {
  for (const StageCost& s : stages)
    if (s.stage == name) return s;
  throw std::runtime_error("no stage " + name);
}

TEST(FrameCostModel, ShadingCountsTheKernelsInterpolationAndDot) {
  const FrameCounts c = counts();
  FrameStageTimes view, light;
  view.view_cache_kernel_ms = 3;
  view.shade_kernel_ms = 4;
  light.shade_kernel_ms = 1;
  const FrameStageCosts f = frame_stage_costs(c, view, light);
  // Per hit: 64 values x 3 channels x (5 + 2).
  const double per_hit = 64 * 3 * (3 * 1 + 2 * 1 + 1 + 1);
  EXPECT_DOUBLE_EQ(stage(f.light, "cached shade").flops, c.hits * per_hit);
  EXPECT_DOUBLE_EQ(stage(f.view, "view cache + shade hits").flops,
                   c.hits * (3 * c.material_flops_per_pixel + per_hit));
  // 3 vertices' 64 x 3 floats, and the pixel, per hit, beside the material's bytes.
  EXPECT_DOUBLE_EQ(stage(f.view, "view cache + shade hits").bytes,
                   c.view_cache_bytes + c.hits * (3 * 64 * 3 * 4 + 12));
  EXPECT_DOUBLE_EQ(stage(f.view, "misses (background)").measured_ms, 1.0);
  // The relight reads the visible share of the transfer and writes the visible vertices' L*.
  const StageCost& relight = stage(f.light, "relight");
  EXPECT_DOUBLE_EQ(relight.bytes, 0.5 * 1e6 + 0.5 * 3286 * 64 * 3 * 4);
  EXPECT_DOUBLE_EQ(relight.flops, 0.5 * 2e7);
}

TEST(FrameCostModel, WithoutADeviceShaderOnlyTheGBufferAndRelightAreModelled) {
  FrameCounts c = counts();
  c.device_shading = false;
  const FrameStageCosts f = frame_stage_costs(c, {}, {});
  ASSERT_EQ(f.view.size(), 2u);
  ASSERT_EQ(f.light.size(), 1u);
  EXPECT_TRUE(stage(f.view, "G-buffer upload").upload);
}

TEST(FrameCostModel, TimeIsTheLargerBoundOrTheLink) {
  const DeviceProfile d{"test", 100.0, 1000.0, 10.0};
  // 1e8 bytes at 100 GB/s: 1 ms; 1e9 FLOPs at 1000 GFLOP/s: 1 ms; 2e9 FLOPs: 2 ms.
  EXPECT_DOUBLE_EQ(model_ms({"a", 1e8, 1e9, false, 0}, d), 1.0);
  EXPECT_DOUBLE_EQ(model_ms({"b", 1e8, 2e9, false, 0}, d), 2.0);
  EXPECT_DOUBLE_EQ(model_ms({"c", 3e8, 1e9, false, 0}, d), 3.0);
  // An upload crosses the host link: 1e8 bytes at 10 GB/s.
  EXPECT_DOUBLE_EQ(model_ms({"d", 1e8, 1e12, true, 0}, d), 10.0);
  const nlohmann::json j = cost_model_json(frame_stage_costs(counts(), {}, {}));
  ASSERT_EQ(j.size(), 6u);
  for (const auto& row : j) EXPECT_EQ(row["model_ms"].size(), model_devices().size());
}

}  // namespace
}  // namespace prt
