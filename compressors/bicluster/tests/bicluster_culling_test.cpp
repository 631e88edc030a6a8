// Backend `bicluster`, culling (bicluster_culling.h): the face masks and the slice subsets
// against independent scans of the arrays, phase 1's face skipping bit-identical to computing
// every bicluster (C++: relight_faces with every face; OpenCL: opencl_skip_faces=false), vertex
// subsets bit-identical to the full relight with the other rows untouched, and the subset
// kernels against their C++ reference.
#include "bicluster/bicluster_culling.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include "bicluster/bicluster.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/opencl/cl_buffer.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/sphere/lit_faces.h"
#include "prtlab/transfer/random_transfer.h"

namespace prt::bicluster {
namespace {

constexpr int kR = 4;

struct Fixture {
  TransferMatrix t = random_transfer(5, RandomTransferSpec{60, 2, kR, 2, 0.5, {7}});
  std::unique_ptr<CompressedTransfer> ct =
      CompressorRegistry::instance()
          .create("bicluster", {})
          ->compress({t, nullptr, CubemapLayout(kR), HemisphereGrid(2)}, Progress::null());
  const BiclusterTransfer& bt() const { return dynamic_cast<const BiclusterTransfer&>(*ct); }
};

const Fixture& fixture() {
  static const Fixture f;
  return f;
}

std::vector<Rgb> light(std::uint32_t dark, std::uint64_t seed) {
  std::vector<Rgb> l(6 * kR * kR);
  std::uint64_t x = seed * 0x9e3779b97f4a7c15ull + 1;
  auto next = [&] {
    x ^= x << 13, x ^= x >> 7, x ^= x << 17;
    return static_cast<float>(x % 1000003) / 1000003.f;
  };
  for (std::size_t k = 0; k < l.size(); ++k) {
    const bool off = (dark >> (k / (kR * kR)) & 1u) != 0;
    l[k] = off ? Rgb(0.f) : Rgb(next(), next(), next());
  }
  return l;
}

bool same_bits(std::span<const Rgb> a, std::span<const Rgb> b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size_bytes()) == 0;
}

TEST(BiclusterCulling, FaceMasksAreTheFacesOfEachBiclustersColumns) {
  const BiclusterArrays& a = fixture().bt().arrays();
  const std::vector<std::uint8_t> faces = bicluster_faces(a);
  ASSERT_EQ(faces.size(), a.bicluster_count());
  std::size_t one_face = 0;
  for (std::size_t i = 0; i < faces.size(); ++i) {
    std::uint32_t want = 0;
    for (std::uint32_t q = a.bic_col_offsets[i]; q < a.bic_col_offsets[i + 1]; ++q)
      want |= 1u << (a.bic_columns[q] / (kR * kR));
    EXPECT_EQ(faces[i], want) << "bicluster " << i;
    if (std::popcount(want) == 1) ++one_face;
  }
  EXPECT_GT(one_face, faces.size() / 2) << "few biclusters a dark face could skip";
}

TEST(BiclusterCulling, SliceSubsetsHoldExactlyTheSubsetsRows) {
  const BiclusterArrays& a = fixture().bt().arrays();
  const std::vector<std::uint32_t> lanes = row_lanes(a);
  const std::vector<std::uint32_t> subset = {0, 1, 7, 20, 59};
  const SliceSubset s = slices_of(a.slice_count(), a.local_count, lanes, subset);
  ASSERT_EQ(s.slices.size(), s.lanes.size());
  std::vector<std::uint32_t> rows_listed;
  for (std::size_t i = 0; i < s.slices.size(); ++i)
    for (int c = 0; c < kSliceRows; ++c)
      if (s.lanes[i] >> c & 1u) rows_listed.push_back(a.slice_rows[s.slices[i] * kSliceRows + c]);
  std::sort(rows_listed.begin(), rows_listed.end());
  std::vector<std::uint32_t> want;
  for (const std::uint32_t v : subset)
    for (int j = 0; j < a.local_count; ++j) want.push_back(v * a.local_count + j);
  EXPECT_EQ(rows_listed, want);
  EXPECT_TRUE(std::is_sorted(s.slices.begin(), s.slices.end()));
}

TEST(BiclusterCulling, DarkFacesAndVertexSubsetsAreBitIdentical) {
  const Fixture& f = fixture();
  const std::vector<std::uint32_t> subset = {2, 3, 10, 33, 59};
  const std::size_t m = static_cast<std::size_t>(f.t.local_count());
  for (const std::uint32_t dark : {0u, 0b010101u, 0b110011u, 0b111111u}) {
    SCOPED_TRACE(::testing::Message() << "dark faces " << dark);
    const LightCoeffs l{"pixel", light(dark, dark + 1)};
    LocalRadiance skipped, every;
    f.bt().relight(l, skipped);
    f.bt().relight_faces(l, kAllFaces, every);
    EXPECT_TRUE(same_bits(skipped.values, every.values));
    LocalRadiance part(RadianceBasis::kPixel, f.t.local_count(), f.t.vertex_count());
    std::fill(part.values.begin(), part.values.end(), Rgb(-5.f));
    f.ct->relight_vertices(l, subset, part);
    for (std::size_t r = 0; r < f.t.rows(); ++r) {
      const bool in = std::binary_search(subset.begin(), subset.end(), r / m);
      const Rgb want = in ? skipped.values[r] : Rgb(-5.f);
      ASSERT_EQ(std::memcmp(&part.values[r], &want, sizeof(Rgb)), 0) << "row " << r;
    }
  }
}

TEST(BiclusterCulling, DeviceSkipsFacesBitIdenticallyAndSubsetKernelsMatchTheCppReference) {
  ClContext* ctx = default_context();
  if (!ctx) GTEST_SKIP() << "no OpenCL device";
  const Fixture& f = fixture();
  const std::vector<std::uint32_t> subset = {0, 4, 5, 6, 41, 58};
  const std::size_t m = static_cast<std::size_t>(f.t.local_count());
  for (const DeviceIds ids : {DeviceIds::kU16, DeviceIds::kU32}) {
    SCOPED_TRACE(std::string("ids ") + std::string(to_string(ids)));
    auto skip = upload_arrays(*ctx, f.bt().arrays(), ids, true);
    auto every = upload_arrays(*ctx, f.bt().arrays(), ids, false);
    for (const std::uint32_t dark : {0u, 0b101010u, 0b011110u}) {
      SCOPED_TRACE(::testing::Message() << "dark faces " << dark);
      const LightCoeffs l{"pixel", light(dark, 3 * dark + 2)};
      LocalRadiance a, b, cpp;
      skip->relight(l, a);
      every->relight(l, b);
      EXPECT_TRUE(same_bits(a.values, b.values)) << "skipping faces changed the device's sums";
      f.ct->relight(l, cpp);
      double err = 0, peak = 0;
      for (std::size_t r = 0; r < f.t.rows(); ++r)
        for (int c = 0; c < 3; ++c) {
          err = std::max(err, static_cast<double>(std::abs(a.values[r][c] - cpp.values[r][c])));
          peak = std::max(peak, static_cast<double>(std::abs(cpp.values[r][c])));
        }
      EXPECT_LE(err, 1e-5 * peak);
      const LightCoeffs other{"pixel", light(0, 1234)};
      LocalRadiance before;
      skip->relight(other, before);
      skip->set_vertex_subset(subset);
      skip->relight_subset_on_device(l);
      std::vector<Rgb> out(f.t.rows());
      download(*ctx, skip->output_buffer(), std::span<Rgb>(out), "test subset");
      for (std::size_t r = 0; r < f.t.rows(); ++r) {
        const bool in = std::binary_search(subset.begin(), subset.end(), r / m);
        const Rgb want = in ? a.values[r] : before.values[r];
        ASSERT_EQ(std::memcmp(&out[r], &want, sizeof(Rgb)), 0) << "row " << r;
      }
    }
  }
}

}  // namespace
}  // namespace prt::bicluster
