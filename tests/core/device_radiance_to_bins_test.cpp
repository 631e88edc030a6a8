// The OpenCL conversion of SH local radiance to the bins against its C++ reference,
// to_pixel_basis.
#include "prtlab/render/device_radiance_to_bins.h"

#include <gtest/gtest.h>

#include <random>

#include "prtlab/opencl/cl_runtime.h"
#include "prtlab/transfer/radiance_to_bins.h"
#include "support/temp_dir.h"

namespace prt {
namespace {

const auto& g_cache = testing::use_private_cache("radiance_to_bins");

TEST(DeviceRadianceToBins, MatchesToPixelBasis) {
  (void)g_cache;
  ClContext* ctx = default_context();
  if (!ctx) GTEST_SKIP() << "no OpenCL device";
  const HemisphereGrid grid(5);
  for (const int order : {1, 3, 5}) {
    const int n = order * order;
    const std::size_t vertices = 37;  // not a multiple of the work-group size
    std::mt19937_64 rng(static_cast<std::uint64_t>(order));
    std::normal_distribution<float> g;
    LocalRadiance sh(RadianceBasis::kSphericalHarmonics, n, vertices);
    for (auto& v : sh.values) v = Rgb(g(rng), g(rng), g(rng));
    const LocalRadiance expected = to_pixel_basis(sh, grid);
    DeviceRadianceToBins convert(*ctx, grid, n, vertices);
    const cl::Buffer in = upload(*ctx, std::span<const Rgb>(sh.values), "test SH radiance");
    EXPECT_GE(convert.run(in), 0.0);
    std::vector<Rgb> got(expected.values.size());
    download(*ctx, convert.output_buffer(), std::span<Rgb>(got), "test bins");
    double worst = 0, largest = 0;
    for (std::size_t i = 0; i < got.size(); ++i) {
      worst = std::max(worst, static_cast<double>(glm::length(got[i] - expected.values[i])));
      largest = std::max(largest, static_cast<double>(glm::length(expected.values[i])));
    }
    EXPECT_LT(worst, 1e-5 * largest) << "order " << order << " on " << ctx->info().label();
  }
}

}  // namespace
}  // namespace prt
