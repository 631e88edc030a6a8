// Image error metrics (image_error.h) against hand-computed values, and the false-colour map.
#include "prtlab/render/image_error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>

#include "prtlab/base/error.h"
#include "prtlab/base/named_warning.h"
#include "prtlab/base/relative_error.h"
#include "prtlab/image/image_io.h"

namespace prt {
namespace {

RgbImage image_of(int w, int h, std::initializer_list<Rgb> pixels) {
  RgbImage img(w, h);
  std::size_t i = 0;
  for (const Rgb& p : pixels) img.pixels.at(i++) = p;
  return img;
}

TEST(ImageError, HandComputedValues) {
  // Reference: (1, 2, 2) and (0, 0, 4): sum b^2 = 9 + 16 = 25.
  // Image:     (1, 2, 3) and (0, 1, 4): differences (0, 0, 1) and (0, 1, 0), sum d^2 = 2.
  const RgbImage ref = image_of(2, 1, {{1, 2, 2}, {0, 0, 4}});
  const RgbImage img = image_of(2, 1, {{1, 2, 3}, {0, 1, 4}});
  const ImageError e = image_error(img, ref);
  EXPECT_EQ(e.pixels, 2u);
  EXPECT_EQ(e.non_finite, 0u);
  EXPECT_NEAR(e.relative_l2, std::sqrt(2.0) / 5.0, 1e-12);
  EXPECT_NEAR(e.rmse, std::sqrt(2.0 / 6.0), 1e-12);
  EXPECT_DOUBLE_EQ(e.max_abs, 1.0);
  EXPECT_DOUBLE_EQ(e.peak, 4.0);
  // PSNR = 20 log10(4 / sqrt(1/3)) = 20 log10(4 sqrt 3) = 16.8124 dB.
  EXPECT_NEAR(e.psnr_db, 20.0 * std::log10(4.0 * std::sqrt(3.0)), 1e-9);
  EXPECT_NEAR(e.psnr_db, 16.8124, 1e-4);
  // The reference is the second argument: swapping changes the normalisation.
  const ImageError swapped = image_error(ref, img);
  EXPECT_NEAR(swapped.relative_l2, std::sqrt(2.0) / std::sqrt(1 + 4 + 9 + 1 + 16.0), 1e-12);
  EXPECT_DOUBLE_EQ(swapped.peak, 4.0);
}

TEST(ImageError, PsnrOfAKnownNoiseLevel) {
  // Every channel off by exactly 0.01 against a peak of 2: PSNR = 20 log10(200) = 46.02 dB,
  // and scaling both images scales RMSE and peak together, leaving PSNR unchanged.
  RgbImage ref(8, 8), img(8, 8);
  for (std::size_t i = 0; i < ref.pixels.size(); ++i) {
    ref.pixels[i] = Rgb(i == 5 ? 2.0f : 0.5f);
    img.pixels[i] = ref.pixels[i] + Rgb(i % 2 ? 0.01f : -0.01f);
  }
  const ImageError e = image_error(img, ref);
  EXPECT_NEAR(e.rmse, 0.01, 1e-7);
  EXPECT_NEAR(e.psnr_db, 20.0 * std::log10(200.0), 1e-4);
  for (auto* im : {&ref, &img})
    for (Rgb& p : im->pixels) p *= 8.f;
  EXPECT_NEAR(image_error(img, ref).psnr_db, e.psnr_db, 1e-4);
  // Identical images: no error, infinite PSNR.
  const ImageError same = image_error(ref, ref);
  EXPECT_EQ(same.relative_l2, 0.0);
  EXPECT_EQ(same.rmse, 0.0);
  EXPECT_TRUE(std::isinf(same.psnr_db) && same.psnr_db > 0);
  // JSON has no infinity: null.
  EXPECT_TRUE(to_json(same)["psnr_db"].is_null());
  EXPECT_EQ(to_json(e)["pixels"], 64);
}

TEST(ImageError, MaskSelectsPixels) {
  const RgbImage ref = image_of(3, 1, {{1, 1, 1}, {2, 2, 2}, {100, 0, 0}});
  const RgbImage img = image_of(3, 1, {{1, 1, 2}, {2, 2, 2}, {0, 0, 0}});
  const std::vector<std::uint8_t> mask = {1, 1, 0};
  const ImageError e = image_error(img, ref, mask);
  EXPECT_EQ(e.pixels, 2u);
  EXPECT_NEAR(e.relative_l2, 1.0 / std::sqrt(3.0 + 12.0), 1e-12);
  EXPECT_DOUBLE_EQ(e.max_abs, 1.0);
  EXPECT_DOUBLE_EQ(e.peak, 2.0);  // the masked-out 100 is not the peak
  const std::vector<std::uint8_t> none = {0, 0, 0};
  EXPECT_EQ(image_error(img, ref, none).pixels, 0u);
  const std::vector<std::uint8_t> wrong = {1, 1};
  EXPECT_THROW(image_error(img, ref, wrong), ParameterError);
}

TEST(ImageError, SizeMismatchNamesBothSizes) {
  try {
    image_error(RgbImage(4, 3), RgbImage(3, 4));
    FAIL() << "no exception";
  } catch (const ParameterError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("4 x 3"), std::string::npos) << what;
    EXPECT_NE(what.find("3 x 4"), std::string::npos) << what;
  }
  EXPECT_THROW(error_false_colour(RgbImage(4, 3), RgbImage(4, 4)), ParameterError);
}

TEST(ImageError, NonFiniteValuesAreReportedNotSkipped) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const RgbImage ref = image_of(2, 1, {{1, 1, 1}, {1, 1, 1}});
  const RgbImage img = image_of(2, 1, {{1, 1, 1}, {nan, 1, 1}});
  const ImageError e = image_error(img, ref);
  EXPECT_EQ(e.non_finite, 1u);
  EXPECT_TRUE(std::isnan(e.relative_l2));
  EXPECT_TRUE(std::isnan(e.rmse));
  EXPECT_TRUE(std::isnan(e.max_abs));
  EXPECT_TRUE(to_json(e)["relative_l2"].is_null());
}

// Against a black reference the relative error and the PSNR are undefined, whether the image is
// black too (0 / 0 is no perfect score) or not; the absolute metrics still say how far off it is.
TEST(ImageError, ZeroReferenceIsUndefinedNotPerfect) {
  const RgbImage zero(2, 2);
  RgbImage img(2, 2);
  const int warned = warning_count(kZeroReferenceWarning);
  const ImageError same = image_error(img, zero);
  EXPECT_TRUE(std::isnan(same.relative_l2));
  EXPECT_TRUE(std::isnan(same.psnr_db));
  EXPECT_EQ(same.rmse, 0.0);
  EXPECT_TRUE(to_json(same)["relative_l2"].is_null());
  img.pixels[1] = Rgb(0.5f);
  const ImageError e = image_error(img, zero);
  EXPECT_TRUE(std::isnan(e.relative_l2));
  EXPECT_TRUE(std::isnan(e.psnr_db));
  EXPECT_NEAR(e.max_abs, 0.5, 1e-7);
  EXPECT_EQ(warning_count(kZeroReferenceWarning), warned + 2);
}

TEST(ImageError, ViridisEndpointsAndLightness) {
  // matplotlib's viridis: #440154 at 0, #21918c at 0.5, #fde725 at 1 (fit within 0.02).
  const Rgb lo = viridis(0), mid = viridis(0.5), hi = viridis(1);
  EXPECT_NEAR(lo.r, 0x44 / 255.f, 0.02f);
  EXPECT_NEAR(lo.g, 0x01 / 255.f, 0.02f);
  EXPECT_NEAR(lo.b, 0x54 / 255.f, 0.02f);
  EXPECT_NEAR(mid.r, 0x21 / 255.f, 0.02f);
  EXPECT_NEAR(mid.g, 0x91 / 255.f, 0.02f);
  EXPECT_NEAR(mid.b, 0x8c / 255.f, 0.02f);
  EXPECT_NEAR(hi.r, 0xfd / 255.f, 0.02f);
  EXPECT_NEAR(hi.g, 0xe7 / 255.f, 0.02f);
  EXPECT_NEAR(hi.b, 0x25 / 255.f, 0.03f);
  // Monotone in luminance (what makes it readable in grey), clamped outside [0, 1].
  double previous = -1;
  for (int i = 0; i <= 100; ++i) {
    const Rgb c = viridis(i / 100.0);
    const double y = 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
    EXPECT_GT(y, previous) << i;
    previous = y;
  }
  EXPECT_EQ(viridis(-3), viridis(0));
  EXPECT_EQ(viridis(7), viridis(1));
}

TEST(ImageError, FalseColourMapsRelativeError) {
  // 4 x 2 reference of 1; errors 0, 0.1, 0.2, 0.4 in the first row, 0 in the second, one
  // pixel masked out.
  RgbImage ref(4, 2), img(4, 2);
  std::fill(ref.pixels.begin(), ref.pixels.end(), Rgb(1.f));
  img.pixels = ref.pixels;
  const float err[4] = {0.f, 0.1f, 0.2f, 0.4f};
  for (int x = 0; x < 4; ++x) img.at(x, 0) = Rgb(1.f + err[x]);
  std::vector<std::uint8_t> mask(8, 1);
  mask[7] = 0;

  const std::vector<double> e = relative_error_map(img, ref, mask);
  // |a - b| / (|b| + eps): the norms are of RGB triples, sqrt(3) err / (sqrt(3) + eps).
  const double eps = 1e-3 * std::sqrt(3.0);
  EXPECT_NEAR(e[3], std::sqrt(3.0) * 0.4 / (std::sqrt(3.0) + eps), 1e-6);
  EXPECT_EQ(e[7], 0.0);

  const FalseColour fixed = error_false_colour(img, ref, mask, 0.4);
  EXPECT_EQ(fixed.scale, 0.4);
  EXPECT_NEAR(fixed.eps, eps, 1e-9);
  ASSERT_EQ(fixed.image.width, 4);
  ASSERT_EQ(fixed.image.height, 2 + 2 + 8);  // image, separator, colour bar of 8 rows
  EXPECT_EQ(fixed.image.at(0, 0), viridis(0));
  const Rgb top = viridis(e[3] / 0.4);
  EXPECT_EQ(fixed.image.at(3, 0), top);
  EXPECT_NEAR(fixed.image.at(3, 0).r, viridis(1).r, 0.01f);
  EXPECT_EQ(fixed.image.at(3, 1), Rgb(0.1f));  // not counted
  EXPECT_EQ(fixed.image.at(2, 2), Rgb(0.f));   // separator
  // Colour bar: left end is 0, right end is the scale; ticks in its upper half.
  EXPECT_EQ(fixed.image.at(0, 11), viridis(0));
  EXPECT_EQ(fixed.image.at(3, 11), viridis(1));
  EXPECT_EQ(fixed.image.at(0, 4), Rgb(1.f));

  // Automatic scale: the 99th percentile of the 7 counted errors, the value of rank
  // floor(0.99 * 6) = 5 (0-based) in increasing order: 0, 0, 0, 0, e1, e2, e3 -> e2.
  const FalseColour automatic = error_false_colour(img, ref, mask);
  EXPECT_DOUBLE_EQ(automatic.scale, e[2]);
  // No error anywhere: scale 1, everything at the bottom of the map.
  const FalseColour none = error_false_colour(ref, ref);
  EXPECT_EQ(none.scale, 1.0);
  EXPECT_EQ(none.image.at(1, 1), viridis(0));
}

TEST(ImageError, FalseColourPngIsWrittenWithoutToneMapping) {
  RgbImage ref(16, 8), img(16, 8);
  for (std::size_t i = 0; i < ref.pixels.size(); ++i) {
    ref.pixels[i] = Rgb(1.f + i);
    img.pixels[i] = ref.pixels[i] * 1.05f;
  }
  const auto dir = std::filesystem::temp_directory_path() / "prtlab_image_error_test";
  std::filesystem::create_directories(dir);
  const auto file = dir / "err.png";
  write_false_colour_png(error_false_colour(img, ref), file);
  EXPECT_TRUE(std::filesystem::exists(file));
  EXPECT_GT(std::filesystem::file_size(file), 0u);
  std::filesystem::remove_all(dir);
}

TEST(ImageError, HitMaskFromGBuffer) {
  GBuffer g;
  g.reset(3, 1);
  g.triangle = {-1, 4, 7};
  g.part = {-1, 0, 1};
  EXPECT_EQ(hit_mask(g), (std::vector<std::uint8_t>{0, 1, 1}));
  EXPECT_EQ(hit_mask(g, 1), (std::vector<std::uint8_t>{0, 0, 1}));
}

}  // namespace
}  // namespace prt
