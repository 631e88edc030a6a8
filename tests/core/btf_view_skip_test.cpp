// The diffuse-BTF skip (docs/btf.md "Diffuse BTFs"): a BTF is treated as view independent
// exactly when every view of every texel holds bitwise the same values; then eval, eval_lights
// and shade read view 0 with weight 1, and they differ from interpolating the 4 equal view
// samples only by the rounding of the interpolation weights, within the bound derived there.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "prtlab/btf/btf.h"
#include "prtlab/btf/btf_generator.h"
#include "prtlab/btf/btf_materials.h"
#include "support/random_directions.h"

namespace prt {
namespace {

constexpr double kUlp = 0x1p-24;  // unit roundoff of float
// docs/btf.md "Diffuse BTFs": |skipped - interpolated| <= c u sum_t w_t |D_t| (D_t the dot
// product of texel t), c = 7 with nearest texels and 24 with bilinear ones (rounded up here).
constexpr double kCppBoundNearest = 8 * kUlp;
constexpr double kCppBoundBilinear = 25 * kUlp;

// Values that depend on texel, light and channel but not on the view: what a Lambertian BTF
// with a texture holds. Light values are not exactly representable sums, so rounding shows.
Btf diffuse_btf(int u, int view_side, int light_side) {
  const int v = view_side * view_side, m = light_side * light_side;
  std::vector<float> rgb(static_cast<std::size_t>(u) * u * v * m * 3);
  for (int t = 0; t < u * u; ++t)
    for (int k = 0; k < v; ++k)
      for (int j = 0; j < m; ++j)
        for (int c = 0; c < 3; ++c)
          rgb[((static_cast<std::size_t>(t) * v + k) * m + j) * 3 + c] =
              0.1f + 0.07f * static_cast<float>((t * 7 + j * 3 + c) % 11) / 3.0f;
  return Btf("diffuse", u, view_side, light_side, std::move(rgb));
}

// The same values with one float of (texel, view, light, channel) moved by one ulp.
Btf with_one_value_changed(const Btf& b, int texel, int view, int light, int channel) {
  std::vector<float> rgb(b.data().begin(), b.data().end());
  float& x = rgb[b.offset(texel, view, light) + static_cast<std::size_t>(channel)];
  x = std::nextafter(x, 1.0f);
  return Btf(b.material(), b.resolution(), b.view_side(), b.light_side(), std::move(rgb));
}

TEST(BtfViewSkip, DetectionIsExact) {
  const Btf b = diffuse_btf(3, 4, 2);
  EXPECT_TRUE(b.view_independent());
  // One ulp anywhere, in any view (the first one too: it is what the skip reads), turns it off.
  for (const auto& [texel, view, light, channel] :
       {std::array{0, 0, 0, 0}, std::array{4, 7, 2, 1}, std::array{8, 15, 3, 2},
        std::array{8, 1, 0, 2}}) {
    EXPECT_FALSE(with_one_value_changed(b, texel, view, light, channel).view_independent())
        << "texel " << texel << " view " << view << " light " << light << " channel " << channel;
  }
  // +0 and -0 compare equal as floats but are different bits: not treated as equal.
  std::vector<float> zeros(static_cast<std::size_t>(1) * 4 * 1 * 3, 0.0f);
  zeros[3 * 2 + 1] = -0.0f;
  EXPECT_FALSE(Btf("zeros", 1, 2, 1, zeros).view_independent());
  zeros[3 * 2 + 1] = 0.0f;
  EXPECT_TRUE(Btf("zeros", 1, 2, 1, zeros).view_independent());
  // One view sample is view independent whatever it holds.
  EXPECT_TRUE(with_one_value_changed(diffuse_btf(2, 1, 2), 1, 0, 1, 0).view_independent());
  // kNever keeps the interpolation (and the values).
  const Btf never = without_view_skip(b);
  EXPECT_FALSE(never.view_independent());
  EXPECT_TRUE(
      std::equal(never.data().begin(), never.data().end(), b.data().begin(), b.data().end()));
}

TEST(BtfViewSkip, GeneratedLambertIsDetectedAndMesoStructureIsNot) {
  BtfParams p;
  p.resolution = 4;
  p.view_side = 4;
  p.light_side = 3;
  p.supersampling = 1;
  p.geometry_grid = 32;
  EXPECT_TRUE(generate_btf(make_btf_material("lambert"), p).view_independent());
  for (const char* name : {"checker", "bumps", "stucco", "stone"})
    EXPECT_FALSE(generate_btf(make_btf_material(name, 32), p).view_independent()) << name;
}

// With nearest texels the skip returns the stored vector itself, bit for bit, at any view
// (inside, at and below the horizon, degenerate).
TEST(BtfViewSkip, NearestSkipReadsTheStoredValues) {
  const Btf b = diffuse_btf(4, 5, 3);
  const int m = b.light_count();
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> uv(-2.0f, 3.0f);
  std::vector<Rgb> out(static_cast<std::size_t>(m)), light(static_cast<std::size_t>(m));
  for (int j = 0; j < m; ++j) light[j] = Rgb(0.5f + j, 1.5f, 0.25f * j);
  std::vector<Vec3> views = {{0.f, 0.f, 1.f}, {1.f, 0.f, 0.f}, {0.f, 0.f, -1.f}, {0.f, 0.f, 0.f}};
  for (int i = 0; i < 200; ++i) views.push_back(Vec3(prt::testing::random_direction(rng)));
  for (const Vec3& e : views) {
    const Vec2 at(uv(rng), uv(rng));
    const int t = b.texel_at(at);
    b.eval_lights(at, e, out);
    Rgb dot(0.0f), magnitude(0.0f);
    for (int j = 0; j < m; ++j) {
      ASSERT_EQ(out[j], b.value(t, 0, j));
      ASSERT_EQ(b.eval(at, e, j), b.value(t, 0, j));
      dot += b.value(t, 0, j) * light[j];
      magnitude += glm::abs(b.value(t, 0, j) * light[j]);
    }
    // The same sum of the stored values, each sum within float's dot-product bound of the
    // exact one (m terms: gamma_m times the sum of magnitudes), so the two within twice it: a
    // build for a CPU with FMA may contract either sum differently.
    const float gamma = m * 0x1p-24f / (1 - m * 0x1p-24f);
    const Rgb shaded = b.shade(at, e, light);
    for (int c = 0; c < 3; ++c) ASSERT_LE(std::abs(shaded[c] - dot[c]), 2 * gamma * magnitude[c]);
    const BtfViewSamples s = b.view_samples(e);
    EXPECT_EQ(s.weight, (std::array<float, 4>{1.0f, 0.0f, 0.0f, 0.0f}));
    EXPECT_EQ(s.view, (std::array<int, 4>{0, 0, 0, 0}));
  }
}

// Skipped vs interpolated: within c u of the skipped value (all values and lights are
// non-negative, so sum_t w_t |D_t| is the shaded value up to its own rounding), and not
// always equal: the skip is not a no-op on the float result.
TEST(BtfViewSkip, SkippedAndInterpolatedAgreeWithinTheDerivedBound) {
  const Btf skip = diffuse_btf(4, 6, 4);
  const Btf full = without_view_skip(skip);
  const int m = skip.light_count();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<float> uv(-1.0f, 2.0f), l(0.0f, 3.0f);
  std::vector<Rgb> light(static_cast<std::size_t>(m)), a(light.size()), b(light.size());
  for (const auto filter : {TexelFilter::kNearest, TexelFilter::kBilinear}) {
    const double bound = filter == TexelFilter::kNearest ? kCppBoundNearest : kCppBoundBilinear;
    double worst_shade = 0, worst_vector = 0;
    int differing = 0;
    for (int i = 0; i < 2000; ++i) {
      for (auto& x : light) x = Rgb(l(rng), l(rng), l(rng));
      const Vec2 at(uv(rng), uv(rng));
      const Vec3 e(prt::testing::random_direction(rng));
      const Rgb s = skip.shade(at, e, light, filter), f = full.shade(at, e, light, filter);
      skip.eval_lights(at, e, a, filter);
      full.eval_lights(at, e, b, filter);
      for (int c = 0; c < 3; ++c) {
        const double rel = std::abs(static_cast<double>(s[c]) - f[c]) / s[c];
        worst_shade = std::max(worst_shade, rel);
        differing += s[c] != f[c];
        for (int j = 0; j < m; ++j)
          worst_vector =
              std::max(worst_vector, std::abs(static_cast<double>(a[j][c]) - b[j][c]) / a[j][c]);
      }
    }
    const char* name = filter == TexelFilter::kNearest ? "nearest" : "bilinear";
    EXPECT_LE(worst_shade, bound) << name << ": worst " << worst_shade / kUlp << " u";
    EXPECT_LE(worst_vector, bound) << name << ": worst " << worst_vector / kUlp << " u";
    EXPECT_GT(differing, 0) << name << ": the interpolated path rounds somewhere";
  }
}

}  // namespace
}  // namespace prt
