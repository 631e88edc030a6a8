// material_error (compress/material_error.h) and the light-basis rules
// (compress/material_light_basis.h): the error of a material whose reflectance is the BTF
// scaled by (1 + k) is exactly k in every relative measure, a single changed sample gives its
// own share, every measure on a hand-computed 1-texel BTF (a zero sample, one under the floor),
// a material of other sampling is refused; shading_light_path and check_light_basis accept what
// shading can use and refuse the rest.
#include "prtlab/compress/material_error.h"

#include <gtest/gtest.h>

#include <cmath>

#include "prtlab/base/error.h"
#include "prtlab/btf/btf_generator.h"
#include "prtlab/btf/btf_materials.h"
#include "prtlab/compress/material_light_basis.h"
#include "prtlab/sphere/hemisphere_grid.h"

namespace prt {
namespace {

// The values of a BTF (a copy) times `scale`, with `bump` added to one sample (texel 1, view 2,
// light 3, red): the material whose error against a BTF each test knows in closed form.
class TableMaterial final : public CompressedMaterial {
 public:
  explicit TableMaterial(Btf values, float scale = 1.0f, float bump = 0.0f)
      : values_(std::move(values)), scale_(scale), bump_(bump) {}
  std::string backend() const override { return "table"; }
  StorageReport storage() const override { return {}; }
  double flops_per_pixel() const override { return 0; }
  double declared_error_bound() const override { return 0; }
  MaterialLightBasis light_basis() const override {
    return MaterialLightBasis::pixel_bins(values_.light_side());
  }
  MaterialSampling sampling() const override { return sampling_of(values_); }
  Rgb reflectance(int texel, int view, int light) const override {
    Rgb v = values_.value(texel, view, light) * scale_;
    if (texel == 1 && view == 2 && light == 3) v.x += bump_;
    return v;
  }
  void eval_lights(Vec2, Vec3, std::span<Rgb>, TexelFilter) const override {}
  std::unique_ptr<DeviceMaterial> upload(ClContext&, std::span<const CompressedMaterial* const>,
                                         const ParamSet&) const override {
    return nullptr;
  }
  void save(ArchiveWriter&) const override {}

 private:
  Btf values_;
  float scale_, bump_;
};

const Btf& small_btf() {
  static const Btf b = [] {
    BtfParams p;
    p.resolution = 4;
    p.view_side = 3;
    p.light_side = 3;
    p.supersampling = 1;
    p.geometry_grid = 32;
    return generate_btf(make_btf_material("checker", 32), p);
  }();
  return b;
}

TEST(MaterialError, IsZeroForTheBtfItselfAndTheScaleOtherwise) {
  const Btf& b = small_btf();
  const MaterialError same = material_error(TableMaterial(b, 1.0f), b);
  EXPECT_EQ(same.relative_l2, 0.0);
  EXPECT_EQ(same.max_abs, 0.0);
  EXPECT_EQ(same.samples, b.value_count());
  EXPECT_GT(same.reference_l2, 0.0);
  EXPECT_EQ(same.average_relative, 0.0);
  EXPECT_EQ(same.average_relative_floored, 0.0);
  EXPECT_EQ(same.average_abs, 0.0);
  EXPECT_EQ(same.cosine_l2, 0.0);
  EXPECT_EQ(same.white_light_l2, 0.0);
  // Halving is exact in float: every relative error is 0.5 to double rounding (the floored one
  // is 0.5 where |b| is above the floor and less below it).
  const MaterialError half = material_error(TableMaterial(b, 0.5f), b);
  EXPECT_NEAR(half.relative_l2, 0.5, 1e-12);
  EXPECT_NEAR(half.average_relative, 0.5, 1e-12);
  EXPECT_NEAR(half.average_relative_worst_abrdf, 0.5, 1e-12);
  EXPECT_LE(half.average_relative_floored, 0.5 + 1e-12);
  EXPECT_GT(half.average_relative_floored, 0.4);
  EXPECT_NEAR(half.cosine_l2, 0.5, 1e-12);
  EXPECT_NEAR(half.white_light_l2, 0.5, 1e-12);
  double abs_sum = 0;
  for (float v : b.data()) abs_sum += 0.5 * std::abs(static_cast<double>(v));
  EXPECT_NEAR(half.average_abs, abs_sum / static_cast<double>(b.value_count()), 1e-12);
}

// One texel, one view, 2 x 2 light bins; red holds a zero and a value under the 1 % floor,
// green and blue are zero everywhere in the material and 1 in the BTF.
TEST(MaterialError, EveryMeasureOnAHandComputedAbrdf) {
  const std::vector<float> full = {2, 1, 1, 0, 1, 1, 0.01f, 1, 1, 4, 1, 1};
  const std::vector<float> approx = {3, 0, 0, 0.5f, 0, 0, 0.02f, 0, 0, 4, 0, 0};
  const Btf b("hand", 1, 1, 2, full);
  const MaterialError e = material_error(TableMaterial(Btf("approx", 1, 1, 2, approx)), b);
  const double red01 = static_cast<double>(0.02f) - static_cast<double>(0.01f);
  ASSERT_NEAR(red01, 0.01, 1e-9);
  // red: |d| = 1, 0.5, 0.01, 0 against 2, 0, 0.01, 4; green and blue: |d| = 1 against 1.
  EXPECT_EQ(e.samples, 12u);
  EXPECT_EQ(e.zero_samples, 1u);
  const double rel = (1.0 / 2 + red01 / static_cast<double>(0.01f) + 0 + 8 * 1.0) / 11;
  EXPECT_NEAR(e.average_relative, rel, 1e-12);
  EXPECT_NEAR(e.average_relative_worst_abrdf, rel, 1e-12) << "one ABRDF: its own mean";
  // The red floor is 0.01 * 4 = 0.04: the zero counts as 0.5 / 0.04, the 0.01 as 0.01 / 0.04.
  const double floored = (1.0 / 2 + 0.5 / 0.04 + red01 / 0.04 + 0 + 8 * 1.0) / 12;
  EXPECT_NEAR(e.average_relative_floored, floored, 1e-9);
  EXPECT_NEAR(e.average_abs, (1.0 + 0.5 + red01 + 0 + 8) / 12, 1e-12);
  const double f001 = static_cast<double>(0.01f);
  EXPECT_NEAR(e.relative_l2,
              std::sqrt((1 + 0.25 + red01 * red01 + 8) / (4 + 0 + f001 * f001 + 16 + 8)), 1e-12);
  // Cosine weights: the 4 cells of a 2 x 2 grid are symmetric, so all c_j are equal and the
  // weighted error is the plain one.
  EXPECT_NEAR(e.cosine_l2, e.relative_l2, 1e-12);
  // White light: red sums d = 1 + 0.5 + 0.01 + 0, b = 6.01; green and blue d = -4, b = 4.
  const double dr = 1.5 + red01, br = 6 + f001;
  EXPECT_NEAR(e.white_light_l2, std::sqrt((dr * dr + 32) / (br * br + 32)), 1e-12);
}

TEST(MaterialError, CosineWeightsAreTheCellMeanCosines) {
  // 3 x 3 light bins, one error of 1 at the zenith bin 4 and one at corner bin 0, against b = 1.
  const int m = 9;
  std::vector<float> full(static_cast<std::size_t>(m) * 3, 1.0f), approx = full;
  approx[4 * 3] += 1.0f;
  approx[0] += 1.0f;
  const MaterialError e =
      material_error(TableMaterial(Btf("approx", 1, 1, 3, approx)), Btf("full", 1, 1, 3, full));
  const HemisphereGrid g(3);
  const std::vector<double> p = g.projected_solid_angles();
  double ref = 0;
  for (double x : p) ref += 3 * x / g.cell_solid_angle();
  const double c0 = p[0] / g.cell_solid_angle(), c4 = p[4] / g.cell_solid_angle();
  ASSERT_GT(c4, 2 * c0) << "the zenith bin's cosine is well above the corner's";
  EXPECT_NEAR(e.cosine_l2, std::sqrt((c0 + c4) / ref), 1e-12);
  EXPECT_NEAR(e.relative_l2, std::sqrt(2.0 / 27), 1e-12);
}

TEST(MaterialError, OneChangedSampleGivesItsShareOfTheNorm) {
  const Btf& b = small_btf();
  const MaterialError e = material_error(TableMaterial(b, 1.0f, 0.5f), b);
  const double bumped = static_cast<double>(b.value(1, 2, 3).x + 0.5f) - b.value(1, 2, 3).x;
  EXPECT_NEAR(e.max_abs, bumped, 1e-7);
  EXPECT_NEAR(e.relative_l2, bumped / e.reference_l2, 1e-12);
  const Rgb ref = b.value(1, 2, 3);
  ASSERT_NE(ref.x, 0.0f);
  EXPECT_NEAR(e.average_relative,
              bumped / std::abs(ref.x) / static_cast<double>(e.samples - e.zero_samples), 1e-12);
  EXPECT_NEAR(e.average_abs, bumped / static_cast<double>(e.samples), 1e-12);
}

TEST(MaterialError, RefusesAMaterialOfOtherSampling) {
  BtfParams p;
  p.resolution = 2;
  p.view_side = 3;
  p.light_side = 3;
  p.supersampling = 1;
  p.geometry_grid = 32;
  const Btf other = generate_btf(make_btf_material("lambert", 32), p);
  EXPECT_THROW(material_error(TableMaterial(other, 1.0f), small_btf()), ParameterError);
}

TEST(MaterialLightBasis, ShadingPathsBetweenTransferOutputAndMaterial) {
  const auto pixel = MaterialLightBasis::pixel_bins(8);
  const auto sh = MaterialLightBasis::spherical_harmonics(4);
  EXPECT_EQ(pixel.dim, 64);
  EXPECT_EQ(sh.dim, 16);
  EXPECT_NE(pixel, MaterialLightBasis::pixel_bins(4));
  EXPECT_EQ(shading_light_path(RadianceBasis::kPixel, pixel, "t", "m"), LightPath::kDirect);
  EXPECT_EQ(shading_light_path(RadianceBasis::kSphericalHarmonics, pixel, "t", "m"),
            LightPath::kToPixelBins);
  EXPECT_EQ(shading_light_path(RadianceBasis::kSphericalHarmonics, sh, "t", "m"),
            LightPath::kDirect);
  try {
    shading_light_path(RadianceBasis::kPixel, sh, "uncompressed", "rtt");
    FAIL() << "a pixel-basis relight was accepted for an SH material";
  } catch (const ParameterError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("uncompressed"), std::string::npos) << msg;
    EXPECT_NE(msg.find("rtt"), std::string::npos) << msg;
  }
}

TEST(MaterialLightBasis, CheckLightBasisComparesBasisDimensionAndVertices) {
  const auto pixel = MaterialLightBasis::pixel_bins(4);
  EXPECT_NO_THROW(check_light_basis(pixel, LocalRadiance(RadianceBasis::kPixel, 16, 5), 5, "t"));
  EXPECT_THROW(check_light_basis(pixel, LocalRadiance(RadianceBasis::kPixel, 9, 5), 5, "t"),
               ParameterError);
  EXPECT_THROW(check_light_basis(pixel, LocalRadiance(RadianceBasis::kPixel, 16, 4), 5, "t"),
               ParameterError);
  EXPECT_THROW(
      check_light_basis(pixel, LocalRadiance(RadianceBasis::kSphericalHarmonics, 16, 5), 5, "t"),
      ParameterError);
  EXPECT_NO_THROW(check_light_basis(MaterialLightBasis::spherical_harmonics(4),
                                    LocalRadiance(RadianceBasis::kSphericalHarmonics, 16, 5), 5,
                                    "t"));
}

}  // namespace
}  // namespace prt
