// SSIM (image/ssim.h): 1 for an image against itself, symmetric, the closed form of single-pixel
// windows and of constant images, agreement with a direct (non-separable) evaluation of the
// windowed sums on a small random image, lower for a distorted image, the mask, and refusals.
#include "prtlab/image/ssim.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "prtlab/base/error.h"

namespace prt {
namespace {

RgbImage random_image(int w, int h, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  RgbImage img(w, h);
  for (Rgb& p : img.pixels) p = Rgb(u(rng), u(rng), u(rng));
  return img;
}

// The paper's definition evaluated directly: weighted sums over the window cut at the border.
double direct_ssim(const RgbImage& a, const RgbImage& b, int px, int py, int c,
                   const SsimOptions& o) {
  double wsum = 0, mx = 0, my = 0, xx = 0, yy = 0, xy = 0;
  for (int y = py - o.radius; y <= py + o.radius; ++y)
    for (int x = px - o.radius; x <= px + o.radius; ++x) {
      if (x < 0 || y < 0 || x >= a.width || y >= a.height) continue;
      const double w =
          std::exp(-((x - px) * (x - px) + (y - py) * (y - py)) / (2 * o.sigma * o.sigma));
      const double u = a.at(x, y)[c], v = b.at(x, y)[c];
      wsum += w;
      mx += w * u;
      my += w * v;
      xx += w * u * u;
      yy += w * v * v;
      xy += w * u * v;
    }
  mx /= wsum;
  my /= wsum;
  const double vx = xx / wsum - mx * mx, vy = yy / wsum - my * my, cov = xy / wsum - mx * my;
  const double c1 = std::pow(o.k1 * o.data_range, 2), c2 = std::pow(o.k2 * o.data_range, 2);
  return (2 * mx * my + c1) * (2 * cov + c2) / ((mx * mx + my * my + c1) * (vx + vy + c2));
}

TEST(Ssim, IsOneForTheImageItselfAndSymmetric) {
  const RgbImage a = random_image(23, 17, 1), b = random_image(23, 17, 2);
  EXPECT_NEAR(ssim(a, a), 1.0, 1e-12);
  EXPECT_NEAR(ssim(a, b), ssim(b, a), 1e-12);
  EXPECT_LT(ssim(a, b), 0.2) << "independent noise has almost no structure in common";
}

TEST(Ssim, SinglePixelWindowsAndConstantImagesHaveTheClosedForm) {
  // Radius 0, or a constant image: no variance, SSIM = (2 x y + C1) / (x^2 + y^2 + C1) * C2 / C2.
  const double c1 = 1e-4;
  RgbImage a(3, 2), b(3, 2);
  for (std::size_t i = 0; i < a.pixels.size(); ++i) {
    a.pixels[i] = Rgb(0.25f, 0.5f, 0.75f);
    b.pixels[i] = Rgb(0.5f, 0.5f, 0.25f);
  }
  const auto form = [&](double x, double y) { return (2 * x * y + c1) / (x * x + y * y + c1); };
  const double want = (form(0.25, 0.5) + 1.0 + form(0.75, 0.25)) / 3;
  EXPECT_NEAR(ssim(a, b), want, 1e-12);
  SsimOptions single;
  single.radius = 0;
  const RgbImage r = random_image(4, 3, 3), s = random_image(4, 3, 4);
  const std::vector<double> map = ssim_map(r, s, single);
  for (std::size_t i = 0; i < map.size(); ++i) {
    double expect = 0;
    for (int c = 0; c < 3; ++c) expect += form(r.pixels[i][c], s.pixels[i][c]) / 3;
    EXPECT_NEAR(map[i], expect, 1e-12) << "pixel " << i;
  }
}

TEST(Ssim, TheSeparableSumsEqualTheDirectWindowedSums) {
  const RgbImage a = random_image(13, 9, 5);
  RgbImage b = a;
  std::mt19937_64 rng(6);
  std::normal_distribution<float> noise(0.0f, 0.1f);
  for (Rgb& p : b.pixels)
    for (int c = 0; c < 3; ++c) p[c] += noise(rng);
  for (const SsimOptions& o : {SsimOptions{}, SsimOptions{0.8, 2, 0.01, 0.03, 2.0}}) {
    const std::vector<double> map = ssim_map(b, a, o);
    for (int y = 0; y < a.height; ++y)
      for (int x = 0; x < a.width; ++x) {
        double expect = 0;
        for (int c = 0; c < 3; ++c) expect += direct_ssim(b, a, x, y, c, o) / 3;
        EXPECT_NEAR(map[static_cast<std::size_t>(y) * a.width + x], expect, 1e-9)
            << "pixel (" << x << ", " << y << "), radius " << o.radius;
      }
  }
  const double noisy = ssim(b, a);
  EXPECT_LT(noisy, 0.99);
  EXPECT_GT(noisy, ssim(random_image(13, 9, 7), a)) << "noise on the image keeps more structure";
}

TEST(Ssim, TheMaskSelectsThePixelsAveraged) {
  const RgbImage a = random_image(8, 4, 8), b = random_image(8, 4, 9);
  const std::vector<double> map = ssim_map(a, b);
  std::vector<std::uint8_t> mask(map.size(), 0);
  mask[3] = mask[20] = 1;
  EXPECT_NEAR(ssim(a, b, mask), (map[3] + map[20]) / 2, 1e-12);
  EXPECT_THROW(ssim(a, b, std::vector<std::uint8_t>(map.size(), 0)), ParameterError);
  EXPECT_THROW(ssim(a, b, std::vector<std::uint8_t>(5, 1)), ParameterError);
  EXPECT_THROW(ssim(a, random_image(8, 5, 1)), ParameterError);
  SsimOptions bad;
  bad.sigma = 0;
  EXPECT_THROW(ssim(a, b, {}, bad), ParameterError);
}

}  // namespace
}  // namespace prt
