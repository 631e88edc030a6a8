// Backend `uncompressed`, culling (uncompressed_culled.h): the face table against the columns,
// face skipping bit-identical to the full product (C++: against relight_exact; OpenCL: against
// the same kernels with opencl_skip_faces=false), vertex subsets bit-identical to the full
// relight with the other rows untouched, and the culled kernels against their C++ reference.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include "prtlab/compress/compressor_registry.h"
#include "prtlab/opencl/cl_buffer.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/sphere/lit_faces.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/transfer/random_transfer.h"
#include "uncompressed/uncompressed.h"

namespace prt::uncompressed {
namespace {

constexpr int kR = 4;

TransferMatrix transfer() {
  return random_transfer(11, RandomTransferSpec{40, 2, kR, 3, 0.6, {5}});
}

// Random positive light, black on `dark` faces.
std::vector<Rgb> light(std::uint32_t dark, std::uint64_t seed) {
  std::vector<Rgb> l(6 * kR * kR);
  std::uint64_t x = seed * 0x9e3779b97f4a7c15ull + 1;
  for (std::size_t k = 0; k < l.size(); ++k) {
    auto next = [&] {
      x ^= x << 13, x ^= x >> 7, x ^= x << 17;
      return static_cast<float>(x % 1000003) / 1000003.f * 0.3f;
    };
    const bool off = (dark >> (k / (kR * kR)) & 1u) != 0;
    l[k] = off ? Rgb(0.f) : Rgb(next(), next(), next());
  }
  return l;
}

bool same_bits(std::span<const Rgb> a, std::span<const Rgb> b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size_bytes()) == 0;
}

TEST(UncompressedCulling, FaceTableSplitsEveryRowAtTheFaceBoundaries) {
  const TransferMatrix t = transfer();
  const FaceTable faces(t);
  ASSERT_FALSE(faces.empty());
  EXPECT_EQ(faces.bytes(), t.rows() * kFaceStarts * 2);
  const auto off = t.row_offsets();
  for (std::size_t r = 0; r < t.rows(); ++r) {
    for (std::uint32_t i = off[r]; i < off[r + 1]; ++i) {
      const int face = static_cast<int>(t.column(i) / (kR * kR));
      const std::uint32_t rel = i - off[r];
      const std::uint32_t begin = face == 0 ? 0 : faces.starts()[r * kFaceStarts + face - 1];
      const std::uint32_t end =
          face == 5 ? off[r + 1] - off[r] : faces.starts()[r * kFaceStarts + face];
      ASSERT_TRUE(begin <= rel && rel < end) << "row " << r << " entry " << rel << " face " << face;
    }
  }
}

TEST(UncompressedCulling, DarkFacesAreSkippedBitIdentically) {
  const TransferMatrix t = transfer();
  const auto ct =
      CompressorRegistry::instance()
          .create("uncompressed", {})
          ->compress({t, nullptr, CubemapLayout(kR), HemisphereGrid(2)}, Progress::null());
  for (const std::uint32_t dark : {0b010101u, 0b111000u, 0b011111u, 0b111111u}) {
    SCOPED_TRACE(::testing::Message() << "dark faces " << dark);
    const LightCoeffs l{"pixel", light(dark, dark)};
    ASSERT_EQ(lit_faces(l.values), kAllFaces & ~dark);
    LocalRadiance skipped;
    ct->relight(l, skipped);
    const LocalRadiance full = relight_exact(t, l.values);
    EXPECT_TRUE(same_bits(skipped.values, full.values));
  }
}

TEST(UncompressedCulling, VertexSubsetsAreBitIdenticalAndLeaveOtherRows) {
  const TransferMatrix t = transfer();
  const auto ct =
      CompressorRegistry::instance()
          .create("uncompressed", {})
          ->compress({t, nullptr, CubemapLayout(kR), HemisphereGrid(2)}, Progress::null());
  ASSERT_TRUE(ct->supports_vertex_subset());
  const std::vector<std::uint32_t> subset = {0, 3, 4, 5, 17, 39};
  for (const std::uint32_t dark : {0u, 0b100101u}) {
    const LightCoeffs l{"pixel", light(dark, 7)};
    LocalRadiance full, part(RadianceBasis::kPixel, t.local_count(), t.vertex_count());
    ct->relight(l, full);
    std::fill(part.values.begin(), part.values.end(), Rgb(-3.f));
    ct->relight_vertices(l, subset, part);
    const std::size_t m = static_cast<std::size_t>(t.local_count());
    for (std::size_t v = 0; v < t.vertex_count(); ++v) {
      const bool in = std::binary_search(subset.begin(), subset.end(), v);
      for (std::size_t j = 0; j < m; ++j) {
        const Rgb want = in ? full.values[v * m + j] : Rgb(-3.f);
        ASSERT_EQ(std::memcmp(&part.values[v * m + j], &want, sizeof(Rgb)), 0)
            << "vertex " << v << (in ? " (in the subset)" : " (outside)");
      }
    }
  }
}

// Device: the culled kernels (uncompressed_rows_faces, uncompressed_vertices) against the C++
// reference (relight_culled) within the suite's 1e-5, and face skipping against the same device
// path summing every face, bit for bit.
TEST(UncompressedCulling, CulledKernelsMatchTheCppReferenceAndSkipBitIdentically) {
  ClContext* ctx = default_context();
  if (!ctx) GTEST_SKIP() << "no OpenCL device";
  const TransferMatrix t = transfer();
  const FaceTable faces(t);
  Options rows;
  rows.kernel = KernelVariant::kRows;
  Options all = rows;
  all.skip_faces = false;
  auto skip = upload_transfer(*ctx, t, rows, &faces);
  auto sum_all = upload_transfer(*ctx, t, all, &faces);
  ASSERT_TRUE(skip->supports_vertex_subset());
  const std::vector<std::uint32_t> subset = {1, 2, 5, 30, 39};
  for (const std::uint32_t dark : {0u, 0b001011u, 0b111110u}) {
    SCOPED_TRACE(::testing::Message() << "dark faces " << dark);
    const LightCoeffs l{"pixel", light(dark, 3)};
    std::vector<Rgb> cpp(t.rows(), Rgb(-1.f));
    relight_culled(t, faces, l.values, lit_faces(l.values), true, {}, cpp);
    LocalRadiance a, b;
    skip->relight(l, a);
    sum_all->relight(l, b);
    EXPECT_TRUE(same_bits(a.values, b.values)) << "skipping faces changed the device's sums";
    double err = 0, peak = 0;
    for (std::size_t r = 0; r < t.rows(); ++r)
      for (int c = 0; c < 3; ++c) {
        err = std::max(err, static_cast<double>(std::abs(a.values[r][c] - cpp[r][c])));
        peak = std::max(peak, static_cast<double>(std::abs(cpp[r][c])));
      }
    EXPECT_LE(err, 1e-5 * peak);
    // Subset: rows of the subset are the full device relight's, the others the previous light's.
    const LightCoeffs other{"pixel", light(0, 99)};
    LocalRadiance before;
    skip->relight(other, before);
    skip->set_vertex_subset(subset);
    skip->relight_subset_on_device(l);
    std::vector<Rgb> out(t.rows());
    download(*ctx, skip->output_buffer(), std::span<Rgb>(out), "test subset");
    const std::size_t m = static_cast<std::size_t>(t.local_count());
    for (std::size_t r = 0; r < t.rows(); ++r) {
      const bool in = std::binary_search(subset.begin(), subset.end(), r / m);
      const Rgb want = in ? a.values[r] : before.values[r];
      ASSERT_EQ(std::memcmp(&out[r], &want, sizeof(Rgb)), 0) << "row " << r;
    }
  }
  Options lanes;
  lanes.kernel = KernelVariant::kLanes;
  EXPECT_FALSE(upload_transfer(*ctx, t, lanes, &faces)->supports_vertex_subset())
      << "the lanes variant has no bit-identical subset kernel";
}

}  // namespace
}  // namespace prt::uncompressed
