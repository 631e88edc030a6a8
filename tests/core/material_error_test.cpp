// material_error (compress/material_error.h) and the light-basis rules
// (compress/material_light_basis.h): the error of a material whose reflectance is the BTF
// scaled by (1 + k) is exactly k, a single changed sample gives its own share, a material of
// other sampling is refused; shading_light_path and check_light_basis accept what shading can
// use and refuse the rest.
#include "prtlab/compress/material_error.h"

#include <gtest/gtest.h>

#include <cmath>

#include "prtlab/base/error.h"
#include "prtlab/btf/btf_generator.h"
#include "prtlab/btf/btf_materials.h"
#include "prtlab/compress/material_light_basis.h"

namespace prt {
namespace {

// The BTF's values times `scale`, and `bump` added to one sample (texel 1, view 2, light 3, red).
class ScaledMaterial final : public CompressedMaterial {
 public:
  ScaledMaterial(const Btf& btf, float scale, float bump = 0.0f)
      : btf_(btf), scale_(scale), bump_(bump) {}
  std::string backend() const override { return "scaled"; }
  StorageReport storage() const override { return {}; }
  double flops_per_pixel() const override { return 0; }
  double declared_error_bound() const override { return 0; }
  MaterialLightBasis light_basis() const override {
    return MaterialLightBasis::pixel_bins(btf_.light_side());
  }
  MaterialSampling sampling() const override { return sampling_of(btf_); }
  Rgb reflectance(int texel, int view, int light) const override {
    Rgb v = btf_.value(texel, view, light) * scale_;
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
  const Btf& btf_;
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
  const MaterialError same = material_error(ScaledMaterial(b, 1.0f), b);
  EXPECT_EQ(same.relative_l2, 0.0);
  EXPECT_EQ(same.max_abs, 0.0);
  EXPECT_EQ(same.samples, b.value_count());
  EXPECT_GT(same.reference_l2, 0.0);
  // Halving is exact in float: the relative error is 0.5 to double rounding.
  EXPECT_NEAR(material_error(ScaledMaterial(b, 0.5f), b).relative_l2, 0.5, 1e-12);
}

TEST(MaterialError, OneChangedSampleGivesItsShareOfTheNorm) {
  const Btf& b = small_btf();
  const MaterialError e = material_error(ScaledMaterial(b, 1.0f, 0.5f), b);
  const double bumped = static_cast<double>(b.value(1, 2, 3).x + 0.5f) - b.value(1, 2, 3).x;
  EXPECT_NEAR(e.max_abs, bumped, 1e-7);
  EXPECT_NEAR(e.relative_l2, bumped / e.reference_l2, 1e-12);
}

TEST(MaterialError, RefusesAMaterialOfOtherSampling) {
  BtfParams p;
  p.resolution = 2;
  p.view_side = 3;
  p.light_side = 3;
  p.supersampling = 1;
  p.geometry_grid = 32;
  const Btf other = generate_btf(make_btf_material("lambert", 32), p);
  EXPECT_THROW(material_error(ScaledMaterial(other, 1.0f), small_btf()), ParameterError);
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
