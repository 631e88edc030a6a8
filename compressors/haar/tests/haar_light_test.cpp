// Backend `haar`, the light's own approximation (Ng 2003; haar_light.h, haar_columns.h): with
// every term the wavelet-basis light relights with the pixel light's bits; truncated to N it
// holds exactly the N best coefficients of a brute-force ranking (coefficients and weights
// computed here from the documented basis functions, not by the backend's transform); the relight
// with it equals the dense product of the stored T~ with it (row and column order alike); the
// device agrees with C++ in both product orders; bad lights are refused by name.
#include "haar/haar_light.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <numeric>
#include <random>

#include "haar/haar.h"
#include "haar/haar_columns.h"
#include "haar/haar_wavelet.h"
#include "haar/tests/stored_terms.h"
#include "prtlab/base/error.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/light_options.h"
#include "prtlab/numeric/float16.h"
#include "prtlab/opencl/cl_buffer.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/transfer/random_transfer.h"
#include "support/temp_dir.h"

namespace prt::haar {
namespace {

const std::filesystem::path g_cache_root = prt::testing::use_private_cache("haar-light");

using namespace prt::haar::test_support;  // compress, arrays, stored_value, stored_index, Params

// A radiance cubemap with a smooth sky, a bright small sun and a dark floor: coefficients of
// every level matter, and no two weighted scores tie.
Cubemap test_environment(int resolution, std::uint64_t seed) {
  Cubemap c(resolution);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  const Vec3d sun = glm::normalize(Vec3d(0.3, 0.8, 0.5));
  for (int k = 0; k < c.layout.pixel_count(); ++k) {
    const Vec3d d = c.layout.direction(k);
    const double up = std::max(0.0, d.y);
    const float spot = glm::dot(d, sun) > 0.97 ? 40.f : 0.f;
    c.radiance[k] = Rgb(static_cast<float>(0.2 + up) + spot + 0.1f * u(rng),
                        static_cast<float>(0.3 + 0.5 * up) + spot + 0.1f * u(rng),
                        static_cast<float>(0.5 + up) + 0.5f * spot + 0.1f * u(rng));
  }
  return c;
}

// The Haar coefficient at index k of a pixel light as the inner product with its basis function,
// built from the documentation in haar_wavelet.h (the value +-1/b on the support), in double.
Vec3d brute_coefficient(std::span<const Rgb> light, const CubemapLayout& layout, int k) {
  const int r = layout.resolution();
  const int face = k / (r * r), x = k % (r * r) % r, y = k % (r * r) / r;
  const HaarSupport s = haar_support(r, x, y);
  Vec3d sum(0.0);
  for (int v = s.y0; v < s.y0 + s.size; ++v)
    for (int u = s.x0; u < s.x0 + s.size; ++u) {
      double sign = 1;
      if (s.split_x && u >= s.x0 + s.size / 2) sign = -sign;
      if (s.split_y && v >= s.y0 + s.size / 2) sign = -sign;
      const Rgb& l = light[layout.index(face, u, v)];
      sum += sign / s.size * Vec3d(l.x, l.y, l.z);
    }
  return sum;
}

double brute_weight(const CubemapLayout& layout, int k, LightWeight w) {
  const int r = layout.resolution();
  const int face = k / (r * r), x = k % (r * r) % r, y = k % (r * r) / r;
  const HaarSupport s = haar_support(r, x, y);
  switch (w) {
    case LightWeight::kNone:
      return 1.0;
    case LightWeight::kFaceArea:
      return 4.0 * s.size * s.size / (static_cast<double>(r) * r);
    case LightWeight::kSolidAngle: {
      double omega = 0;
      for (int v = s.y0; v < s.y0 + s.size; ++v)
        for (int u = s.x0; u < s.x0 + s.size; ++u)
          omega += layout.solid_angle(layout.index(face, u, v));
      return omega;
    }
  }
  return 0;
}

std::vector<std::uint32_t> nonzero_indices(const LightCoeffs& l) {
  std::vector<std::uint32_t> out;
  for (std::size_t k = 0; k < l.values.size(); ++k)
    if (l.values[k].x != 0.f || l.values[k].y != 0.f || l.values[k].z != 0.f)
      out.push_back(static_cast<std::uint32_t>(k));
  return out;
}

const std::vector<Params> kVariants = {
    {{"values", "float32"}, {"k", "7"}},
    {{"values", "float16"}, {"k", "7"}},
    {{"values", "s8"}, {"k", "12"}},
    {{"values", "s8"}, {"k", "300"}, {"index", "u32"}},
    {{"values", "float16"}, {"k", "4"}, {"budget", "global"}, {"scaling", "always"}},
};

TransferMatrix test_transfer(int resolution, std::uint64_t seed) {
  return random_transfer(seed, RandomTransferSpec{12, 2, resolution, 3, 0.5, {5}});
}

TEST(HaarLight, WeightsAreTheSupportsAreaAndSolidAngle) {
  const CubemapLayout layout(8);
  for (LightWeight w : {LightWeight::kSolidAngle, LightWeight::kFaceArea, LightWeight::kNone}) {
    const auto weights = light_weights(layout, w);
    ASSERT_EQ(weights.size(), 384u);
    for (int k = 0; k < 384; ++k)
      ASSERT_NEAR(weights[k], brute_weight(layout, k, w), 1e-12) << to_string(w) << " " << k;
  }
  // The six scaling coefficients' supports are the faces: the sphere, and the cube's area.
  double omega = 0, area = 0;
  const auto sa = light_weights(layout, LightWeight::kSolidAngle);
  const auto fa = light_weights(layout, LightWeight::kFaceArea);
  for (int f = 0; f < 6; ++f) {
    omega += sa[layout.index(f, 0, 0)];
    area += fa[layout.index(f, 0, 0)];
  }
  EXPECT_NEAR(omega, 4 * M_PI, 1e-9);
  EXPECT_NEAR(area, 24.0, 1e-12);
  EXPECT_EQ(light_weight_from("face_area"), LightWeight::kFaceArea);
  try {
    (void)light_weight_from("area");
    FAIL() << "an unknown weight accepted";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("solid_angle"), std::string::npos) << e.what();
  }
}

TEST(HaarLight, EveryTermRelightsWithThePixelLightsBits) {
  const TransferMatrix t = test_transfer(8, 4);
  const Cubemap env = test_environment(8, 1);
  const std::vector<std::uint32_t> subset = {0, 5, 11};
  for (const Params& p : kVariants) {
    const auto ct = compress(t, p);
    const auto& h = dynamic_cast<const HaarTransfer&>(*ct);
    const LightCoeffs pixel = ct->project_light(env);
    LocalRadiance exact;
    ct->relight(pixel, exact);
    for (std::size_t terms : {std::size_t{0}, t.cols(), 10 * t.cols()}) {
      const LightCoeffs all = h.project_light(env, {terms, LightWeight::kSolidAngle});
      EXPECT_EQ(all.basis, kLightBasis);
      LocalRadiance x;
      ct->relight(all, x);
      ASSERT_EQ(x.values.size(), exact.values.size());
      EXPECT_EQ(std::memcmp(x.values.data(), exact.values.data(), x.values.size() * sizeof(Rgb)), 0)
          << "terms = " << terms;
      LocalRadiance part = x;
      std::fill(part.values.begin(), part.values.end(), Rgb(-1.f, -1.f, -1.f));
      ct->relight_vertices(all, subset, part);
      const std::size_t m = t.local_count();
      for (std::uint32_t v : subset)
        for (std::size_t j = 0; j < m; ++j)
          ASSERT_EQ(std::memcmp(&part.values[v * m + j], &exact.values[v * m + j], sizeof(Rgb)), 0);
    }
  }
}

// The registry's light options (light_options.h) reach the same approximation as the backend's
// own call, bit for bit: light_terms = N with its weight, 0 or N >= pixels the pixel light; an
// unknown option or value is refused naming the backend's light options.
TEST(HaarLight, LightOptionsProjectAsTheBackendsOwnApproximation) {
  const TransferMatrix t = test_transfer(8, 4);
  const Cubemap env = test_environment(8, 1);
  const auto ct = compress(t, {{"k", "12"}});
  const auto& h = dynamic_cast<const HaarTransfer&>(*ct);
  for (const auto& [weight, name] :
       std::vector<std::pair<LightWeight, std::string>>{{LightWeight::kSolidAngle, "solid_angle"},
                                                        {LightWeight::kFaceArea, "face_area"},
                                                        {LightWeight::kNone, "none"}}) {
    const LightCoeffs own = h.project_light(env, {20, weight});
    const LightCoeffs via =
        project_light_with(*ct, env, {{"light_terms", "20"}, {"light_weight", name}});
    EXPECT_EQ(via.basis, kLightBasis);
    ASSERT_EQ(via.values.size(), own.values.size());
    EXPECT_EQ(std::memcmp(via.values.data(), own.values.data(), own.values.size() * sizeof(Rgb)), 0)
        << name;
    EXPECT_EQ(nonzero_indices(via).size(), 20u) << name;
  }
  const LightCoeffs pixel = ct->project_light(env);
  for (const char* all : {"0", "384", "100000"}) {
    const LightCoeffs l = project_light_with(*ct, env, {{"light_terms", all}});
    EXPECT_EQ(l.basis, "pixel") << all;
    EXPECT_EQ(std::memcmp(l.values.data(), pixel.values.data(), pixel.values.size() * sizeof(Rgb)),
              0)
        << all;
  }
  for (const std::map<std::string, std::string>& bad :
       std::vector<std::map<std::string, std::string>>{
           {{"terms", "20"}}, {{"light_terms", "-1"}}, {{"light_weight", "area"}}}) {
    try {
      (void)project_light_with(*ct, env, bad);
      ADD_FAILURE() << "accepted " << bad.begin()->first;
    } catch (const ParameterError& e) {
      EXPECT_NE(std::string(e.what()).find("haar (light options)"), std::string::npos) << e.what();
    }
  }
  // A backend without light options refuses any.
  const auto plain =
      CompressorRegistry::instance()
          .create("uncompressed", {})
          ->compress({t, nullptr, CubemapLayout(8), HemisphereGrid(2)}, Progress::null());
  EXPECT_THROW((void)project_light_with(*plain, env, {{"light_terms", "20"}}), ParameterError);
}

TEST(HaarLight, TruncationKeepsExactlyTheBestWeightedCoefficients) {
  const CubemapLayout layout(8);
  const Cubemap env = test_environment(8, 2);
  const std::vector<Rgb> light = env.light_vector();
  std::vector<Vec3d> coefficients;
  for (int k = 0; k < layout.pixel_count(); ++k)
    coefficients.push_back(brute_coefficient(light, layout, k));
  std::vector<std::vector<std::uint32_t>> kept_by_weight;
  for (LightWeight w : {LightWeight::kSolidAngle, LightWeight::kFaceArea, LightWeight::kNone}) {
    std::vector<std::pair<double, std::uint32_t>> ranked;
    for (int k = 0; k < layout.pixel_count(); ++k)
      ranked.push_back({glm::length(coefficients[k]) * brute_weight(layout, k, w),
                        static_cast<std::uint32_t>(k)});
    std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
      return a.first != b.first ? a.first > b.first : a.second < b.second;
    });
    // Scores differing by less than float rounding would make the choice depend on it.
    for (std::size_t i = 0; i + 1 < 120; ++i)
      ASSERT_GT(ranked[i].first - ranked[i + 1].first, 1e-5 * ranked[i].first) << i;
    for (std::size_t n : {1, 5, 25, 50, 119}) {
      SCOPED_TRACE(::testing::Message() << to_string(w) << " N = " << n);
      const LightCoeffs l = approximate_light(light, layout, {n, w});
      std::vector<std::uint32_t> expected;
      for (std::size_t i = 0; i < n; ++i) expected.push_back(ranked[i].second);
      std::sort(expected.begin(), expected.end());
      const auto kept = nonzero_indices(l);
      ASSERT_EQ(kept, expected);
      for (std::uint32_t k : kept)
        for (int c = 0; c < 3; ++c)
          ASSERT_NEAR(l.values[k][c], coefficients[k][c], 1e-5 * glm::length(coefficients[k]));
      if (n == 25) kept_by_weight.push_back(kept);
    }
  }
  // The readings are different rankings (else measuring both would say nothing).
  EXPECT_NE(kept_by_weight[0], kept_by_weight[2]);
  EXPECT_NE(kept_by_weight[1], kept_by_weight[2]);
}

TEST(HaarLight, TruncatedRelightIsTheDenseProductOfTheStoredTransfer) {
  const TransferMatrix t = test_transfer(8, 5);
  const Cubemap env = test_environment(8, 3);
  for (const Params& p : kVariants) {
    const auto ct = compress(t, p);
    const auto& h = dynamic_cast<const HaarTransfer&>(*ct);
    const HaarArrays& a = arrays(*ct);
    const HaarColumns columns(a);
    const HaarColumns small_blocks(a, 7);  // rows split over many blocks
    for (std::size_t n : {1, 25, 100, 384}) {
      SCOPED_TRACE(::testing::Message() << "N = " << n);
      const LightCoeffs l = h.project_light(env, {n, LightWeight::kSolidAngle});
      LocalRadiance rows;
      ct->relight(l, rows);
      const SparseLight sparse = sparse_terms(l.values);
      ASSERT_LE(sparse.indices.size(), n);
      std::vector<Rgb> by_columns(a.rows()), by_small_blocks(a.rows());
      columns.relight(sparse, by_columns);
      small_blocks.relight(sparse, by_small_blocks);
      EXPECT_EQ(std::memcmp(by_columns.data(), by_small_blocks.data(), a.rows() * sizeof(Rgb)), 0)
          << "the block size changed a sum";
      std::uint64_t touched = 0;
      // The stored T~ as a dense matrix of wavelet coefficients times the truncated light.
      for (std::size_t row = 0; row < a.rows(); ++row) {
        std::vector<double> dense(a.pixel_count, 0.0);
        for (std::uint32_t i = a.offsets[row]; i < a.offsets[row + 1]; ++i)
          dense[stored_index(a, i)] = stored_value(a, row, i);
        for (int c = 0; c < 3; ++c) {
          double sum = 0, magnitude = 0;
          for (int k = 0; k < a.pixel_count; ++k) {
            sum += dense[k] * l.values[k][c];
            magnitude += std::abs(dense[k] * l.values[k][c]);
          }
          // Float sums of at most `count` products (and the s8 scale): a few ulps of each term.
          const double bound = 4.0 * (a.count(row) + 2) * FLT_EPSILON * magnitude + 1e-30;
          ASSERT_NEAR(rows.values[row][c], sum, bound) << "row " << row;
          ASSERT_NEAR(by_columns[row][c], sum, bound) << "row " << row << " (columns)";
        }
        for (std::uint32_t i = a.offsets[row]; i < a.offsets[row + 1]; ++i)
          touched +=
              std::binary_search(sparse.indices.begin(), sparse.indices.end(), stored_index(a, i));
      }
      EXPECT_EQ(columns.touched_terms(sparse), touched);
      EXPECT_EQ(small_blocks.touched_terms(sparse), touched);
      if (n == 384) {
        EXPECT_EQ(touched, a.terms());
      }
    }
  }
}

TEST(HaarLight, RefusesALightOfAnotherBasisOrSize) {
  const TransferMatrix t = test_transfer(4, 6);
  const auto ct = compress(t, {});
  for (const LightCoeffs& bad :
       {LightCoeffs{"sh5", std::vector<Rgb>(t.cols())},
        LightCoeffs{std::string(kLightBasis), std::vector<Rgb>(t.cols() - 1)}}) {
    LocalRadiance out;
    try {
      ct->relight(bad, out);
      FAIL() << "basis " << bad.basis << " accepted";
    } catch (const ParameterError& e) {
      EXPECT_NE(std::string(e.what()).find("haar"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(bad.basis), std::string::npos) << e.what();
    }
  }
}

TEST(HaarLight, OpenClMatchesTheCppRelightOfATruncatedLightInBothOrders) {
  ClContext* ctx = default_context();
  if (ctx == nullptr) GTEST_SKIP() << "no OpenCL device";
  // R = 16 and 48 rows; R = 4 and 2,400 rows, more than one 2,048-row column block.
  for (const auto& [r, vertices] :
       {std::pair{16, std::size_t{12}}, std::pair{4, std::size_t{600}}}) {
    const TransferMatrix t = random_transfer(8, RandomTransferSpec{vertices, 2, r, 3, 0.5, {5}});
    const Cubemap env = test_environment(r, 4);
    const std::vector<std::uint32_t> subset = {0, 3, 4, 11};
    for (const Params& p : kVariants) {
      const auto ct = compress(t, p);
      const auto& h = dynamic_cast<const HaarTransfer&>(*ct);
      auto device = upload_compressed(*ct, *ctx);
      ASSERT_NE(device, nullptr);
      auto by_columns = upload_compressed(*ct, *ctx, {{"opencl_order", "columns"}});
      ASSERT_NE(by_columns, nullptr);
      EXPECT_FALSE(by_columns->supports_vertex_subset());
      const HaarColumns columns(arrays(*ct), 2048);
      for (std::size_t n : {25, 200, 0}) {
        SCOPED_TRACE(::testing::Message() << "N = " << n);
        const LightCoeffs l = h.project_light(env, {n, LightWeight::kFaceArea});
        LocalRadiance cpp, gpu, gpu_columns;
        ct->relight(l, cpp);
        device->relight(l, gpu);
        EXPECT_LE(max_relative_error(gpu, cpp), 1e-5);
        // The column kernel sums in the C++ column product's order (columns rising, each block's
        // rows apart): within float rounding of it and of the row order.
        by_columns->relight(l, gpu_columns);
        LocalRadiance cpp_columns(RadianceBasis::kPixel, cpp.dim, cpp.vertices);
        columns.relight(sparse_terms(l.values), cpp_columns.values);
        EXPECT_LE(max_relative_error(gpu_columns, cpp_columns), 1e-6);
        EXPECT_LE(max_relative_error(gpu_columns, cpp), 1e-5);
        device->set_vertex_subset(subset);
        EXPECT_GE(device->relight_subset_on_device(l), 0.0);
        std::vector<Rgb> after(gpu.values.size());
        download(*ctx, device->output_buffer(), std::span<Rgb>(after), "haar light test output");
        const std::size_t m = t.local_count();
        for (std::uint32_t v : subset)
          for (std::size_t j = 0; j < m; ++j)
            ASSERT_EQ(std::memcmp(&after[v * m + j], &gpu.values[v * m + j], sizeof(Rgb)), 0);
      }
      // Back to a pixel light: the device transforms it again (nothing of the last one stays),
      // and the column order reads every column.
      LocalRadiance cpp, gpu, gpu_columns;
      const LightCoeffs pixel = ct->project_light(env);
      ct->relight(pixel, cpp);
      device->relight(pixel, gpu);
      by_columns->relight(pixel, gpu_columns);
      EXPECT_LE(max_relative_error(gpu, cpp), 1e-5);
      EXPECT_LE(max_relative_error(gpu_columns, cpp), 1e-5);
    }
  }
}

}  // namespace
}  // namespace prt::haar
