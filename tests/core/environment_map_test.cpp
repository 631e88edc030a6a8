// Lat-long environment maps: the direction convention, exact texel solid angles, EXR loading
// (invalid values, bad files) and the exact-overlap resampling onto the cubemap.
#include "prtlab/lighting/environment_map.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "prtlab/storage/data_paths.h"
#include "prtlab/base/error.h"
#include "prtlab/image/image_io.h"
#include "prtlab/base/log.h"

namespace prt {
namespace {

namespace fs = std::filesystem;
constexpr std::uint64_t kSeed = 20240602;

fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() /
                       ("prtlab_env_test_" + name + "_" +
                        std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

double max_rel(const Vec3d& a, const Vec3d& b) {
  double m = 0;
  for (int c = 0; c < 3; ++c)
    m = std::max(m, std::abs(a[c] - b[c]) / std::max(std::abs(b[c]), 1e-300));
  return m;
}

LatLongImage image_of(int w, int h, const std::function<Rgb(int, int)>& f) {
  LatLongImage img;
  img.width = w;
  img.height = h;
  img.texels.resize(static_cast<std::size_t>(w) * h);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) img.texels[static_cast<std::size_t>(r) * w + c] = f(c, r);
  return img;
}

double angle_between(const Vec3d& a, const Vec3d& b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

// --- convention --------------------------------------------------------------------------

TEST(LatLong, DocumentedAxes) {
  auto near = [](const Vec3d& a, const Vec3d& b) { return glm::length(a - b) < 1e-12; };
  EXPECT_TRUE(near(latlong_direction(0.5, 0.5), {0, 0, 1}));   // image centre: +Z
  EXPECT_TRUE(near(latlong_direction(0.25, 0.5), {1, 0, 0}));  // a quarter across: +X
  EXPECT_TRUE(near(latlong_direction(0.75, 0.5), {-1, 0, 0}));
  EXPECT_TRUE(near(latlong_direction(0.0, 0.5), {0, 0, -1}));  // the seam: -Z
  EXPECT_TRUE(near(latlong_direction(0.3, 0.0), {0, 1, 0}));   // row 0: zenith
  EXPECT_TRUE(near(latlong_direction(0.3, 1.0), {0, -1, 0}));
}

TEST(LatLong, RoundTripBothWays) {
  std::mt19937_64 rng(kSeed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::normal_distribution<double> g;
  for (int i = 0; i < 20000; ++i) {
    const double u = uni(rng), v = 1e-6 + (1 - 2e-6) * uni(rng);
    const Vec2d uv = direction_to_latlong(latlong_direction(u, v));
    ASSERT_NEAR(uv.y, v, 1e-12);
    // u is periodic; near the poles it is ill-conditioned, so compare directions too.
    const double du = std::abs(uv.x - u);
    ASSERT_LT(std::min(du, 1 - du), 1e-9 / std::sin(kPi * v)) << "u " << u << " v " << v;
    ASSERT_GE(uv.x, 0.0);
    ASSERT_LT(uv.x, 1.0);

    Vec3d d{g(rng), g(rng), g(rng)};
    d = glm::normalize(d);
    const Vec2d e = direction_to_latlong(d * 3.0);  // need not be normalised
    ASSERT_LT(glm::length(latlong_direction(e.x, e.y) - d), 1e-12);
  }
  const Vec2d pole = direction_to_latlong({0, 2, 0});
  EXPECT_EQ(pole.y, 0.0);
  EXPECT_EQ(direction_to_latlong({0, -1, 0}).y, 1.0);
}

TEST(LatLong, TexelSolidAnglesSumToFourPi) {
  for (auto [w, h] : {std::pair{1024, 512}, {7, 3}, {1, 1}, {64, 1000}}) {
    LatLongImage img;
    img.width = w;
    img.height = h;
    double sum = 0;
    for (int r = 0; r < h; ++r) {
      const double omega = img.texel_solid_angle(r);
      // Exact formula, evaluated independently (cos difference directly).
      EXPECT_NEAR(omega, kTwoPi / w * (std::cos(kPi * r / h) - std::cos(kPi * (r + 1) / h)), 1e-14);
      EXPECT_NEAR(omega, img.texel_solid_angle(h - 1 - r), 1e-15);  // symmetric rows
      sum += omega * w;
    }
    EXPECT_NEAR(sum, kFourPi, 1e-12) << w << "x" << h;
  }
}

TEST(LatLong, TotalPowerOfConstantIsFourPiTimesValue) {
  const LatLongImage img = image_of(100, 50, [](int, int) { return Rgb(1.f, 2.f, 0.5f); });
  const Vec3d p = img.total_power();
  EXPECT_NEAR(p.x, kFourPi, 1e-12);
  EXPECT_NEAR(p.y, 2 * kFourPi, 1e-12);
  EXPECT_NEAR(p.z, 0.5 * kFourPi, 1e-12);
}

// --- resampling --------------------------------------------------------------------------

// (lat-long width, height, cubemap R): pixels much larger than texels, comparable, smaller,
// an odd R (a pixel then contains each pole) and odd image sizes.
class Resample : public ::testing::TestWithParam<std::tuple<int, int, int>> {};

TEST_P(Resample, ConstantStaysConstant) {
  const auto [w, h, r] = GetParam();
  const Rgb value(0.75f, 1.5f, 3.0f);
  const Cubemap cube = resample_to_cubemap(image_of(w, h, [&](int, int) { return value; }), r);
  double worst = 0;
  int worst_k = -1;
  for (int k = 0; k < cube.layout.pixel_count(); ++k) {
    for (int c = 0; c < 3; ++c) {
      const double rel = std::abs(cube.radiance[k][c] - value[c]) / value[c];
      if (rel > worst) worst = rel, worst_k = k;
    }
  }
  // The overlaps are exact, so this is float rounding; the brief's bound is 1e-4.
  EXPECT_LT(worst, 1e-5) << "worst pixel " << worst_k;
}

TEST_P(Resample, RandomImagePowerPreserved) {
  const auto [w, h, r] = GetParam();
  std::mt19937_64 rng(kSeed + w + h + r);
  std::exponential_distribution<float> ex(1.0f);
  const LatLongImage img =
      image_of(w, h, [&](int, int) { return Rgb(ex(rng), ex(rng), 10.f * ex(rng)); });
  const Cubemap cube = resample_to_cubemap(img, r);
  EXPECT_LT(max_rel(cube.total_power(), img.total_power()), 1e-6)
      << "image " << img.total_power().x << " cubemap " << cube.total_power().x;
}

INSTANTIATE_TEST_SUITE_P(Sizes, Resample,
                         ::testing::Values(std::tuple{1024, 512, 32}, std::tuple{256, 128, 64},
                                           std::tuple{64, 32, 33}, std::tuple{16, 8, 64},
                                           std::tuple{7, 5, 8}, std::tuple{200, 100, 1},
                                           std::tuple{3, 2, 5}));

// One bright texel at a time, at the poles, the seam and elsewhere: all of its power arrives,
// and only in pixels that touch the texel.
TEST(ResampleDelta, SingleTexelLandsWhereItIs) {
  const int w = 48, h = 24, r = 16;
  const double texel_radius = kPi / h * 0.75;  // half-diagonal of a texel, generous
  const double pixel_radius = 2.0 / r * 0.8;   // half-diagonal of the largest cube pixel
  const std::pair<int, int> cells[] = {{0, 0},   {17, 0},  {47, 23}, {0, 11},
                                       {47, 12}, {12, 12}, {30, 5},  {5, 19}};
  for (auto [col, row] : cells) {
    LatLongImage img = image_of(w, h, [](int, int) { return Rgb(0.f); });
    img.texels[static_cast<std::size_t>(row) * w + col] = Rgb(1.f, 2.f, 3.f);
    const Cubemap cube = resample_to_cubemap(img, r);
    // Float storage of the pixel values limits this to a few float ulps.
    EXPECT_LT(max_rel(cube.total_power(), img.total_power()), 2e-7) << col << "," << row;
    const Vec3d centre = latlong_direction((col + 0.5) / w, (row + 0.5) / h);
    for (int k = 0; k < cube.layout.pixel_count(); ++k) {
      if (cube.radiance[k].x != 0.f) {
        EXPECT_LT(angle_between(cube.layout.direction(k), centre), texel_radius + pixel_radius)
            << "texel " << col << "," << row << " leaked into pixel " << k;
      }
    }
  }
}

// A smooth, asymmetric environment: each pixel's value is close to the function at the pixel
// centre. A flipped or rotated convention would be off by O(1).
TEST(ResampleOrientation, MatchesSmoothFunctionAtPixelCentres) {
  auto f = [](const Vec3d& d) { return Rgb(2.0 + d.x, 2.0 + d.y, 2.0 + d.z); };
  const int w = 512, h = 256, r = 16;
  const LatLongImage img = image_of(
      w, h, [&](int c, int row) { return f(latlong_direction((c + 0.5) / w, (row + 0.5) / h)); });
  const Cubemap cube = resample_to_cubemap(img, r);
  double worst = 0;
  for (int k = 0; k < cube.layout.pixel_count(); ++k) {
    const Rgb expected = f(cube.layout.direction(k));
    for (int c = 0; c < 3; ++c)
      worst = std::max(worst, double(std::abs(cube.radiance[k][c] - expected[c])));
  }
  EXPECT_LT(worst, 0.01);
}

TEST(ResampleBlender, EveryEnvmapPreservesPowerAtR32) {
  const fs::path dir = data_dir() / "envmaps";
  const char* names[] = {"city",  "courtyard", "forest",  "interior",
                         "night", "studio",    "sunrise", "sunset"};
  if (!fs::exists(dir / "courtyard.exr")) {
    GTEST_SKIP() << "data cache missing (" << dir.string() << "); run scripts/setup.sh --data";
  }
  for (const char* name : names) {
    const fs::path file = dir / (std::string(name) + ".exr");
    ASSERT_TRUE(fs::exists(file)) << file;
    const LatLongImage img = load_latlong_exr(file);
    const Cubemap cube = resample_to_cubemap(img, 32);
    const Vec3d before = img.total_power(), after = cube.total_power();
    const double rel = max_rel(after, before);
    std::printf("  %-10s power %.5g %.5g %.5g  relative difference %.2e\n", name, before.x,
                before.y, before.z, rel);
    EXPECT_LT(rel, 0.005) << name;
    EXPECT_GT(before.x, 0.0) << name;
  }
}

// --- SunSky ------------------------------------------------------------------------------

// Reference for the cap/plane area: midpoint rule over the cap in its own polar coordinates.
double cap_above_numeric(double radius, double elevation) {
  const int n_rho = 200, n_psi = 2000;
  double area = 0;
  for (int i = 0; i < n_rho; ++i) {
    const double rho = (i + 0.5) * radius / n_rho;
    int inside = 0;
    for (int j = 0; j < n_psi; ++j) {
      const double psi = (j + 0.5) * kTwoPi / n_psi;
      // Height above the plane of the point at angular distance rho, azimuth psi.
      inside += std::cos(rho) * std::sin(elevation) +
                    std::sin(rho) * std::cos(elevation) * std::cos(psi) >=
                0;
    }
    area += std::sin(rho) * (radius / n_rho) * kTwoPi * inside / n_psi;
  }
  return area;
}

TEST(SunSky, CapAreaAbovePlaneMatchesNumericIntegral) {
  for (double radius : {0.05, 0.3, 1.0, kPi / 2}) {
    for (double frac : {-1.5, -1.0, -0.7, -0.2, 0.0, 0.1, 0.5, 0.99, 1.0, 2.0}) {
      const double elev = std::clamp(frac * radius, -kPi / 2, kPi / 2);
      const double exact = cap_area_above_plane(radius, elev);
      const double numeric = cap_above_numeric(radius, elev);
      EXPECT_NEAR(exact, numeric, 2e-3 * kTwoPi * (1 - std::cos(radius)))
          << "radius " << radius << " elevation " << elev;
    }
  }
  // Symmetry: the two sides of the plane add up to the whole cap.
  EXPECT_NEAR(cap_area_above_plane(0.2, 0.07) + cap_area_above_plane(0.2, -0.07),
              kTwoPi * (1 - std::cos(0.2)), 1e-13);
}

// Latlong -> cubemap power vs the closed form: checks the texel solid angles and the resampling
// against an analytic integral, for a sun high in the sky, straddling the horizon and below it.
TEST(SunSky, ResampledPowerMatchesClosedForm) {
  for (Vec3d sun_dir : {Vec3d{0.3, 0.8, 0.5}, Vec3d{0.6, 0.02, -0.8}, Vec3d{-0.2, -0.5, 0.4}}) {
    SunSky env;
    env.sun_dir = sun_dir;
    const LatLongImage img = env.to_latlong(512, 256);
    const Cubemap cube = resample_to_cubemap(img, 32);
    const Vec3d closed = env.total_power();
    std::printf("  sun (%g, %g, %g): closed form %.6g, lat-long %.6g, cubemap %.6g (red)\n",
                sun_dir.x, sun_dir.y, sun_dir.z, closed.x, img.total_power().x,
                cube.total_power().x);
    EXPECT_LT(max_rel(cube.total_power(), closed), 0.01) << "sun " << sun_dir.x << "," << sun_dir.y;
    EXPECT_LT(max_rel(cube.total_power(), img.total_power()), 1e-6);
  }
  SunSky no_sun;
  no_sun.sun = no_sun.sky;
  EXPECT_LT(max_rel(no_sun.total_power(), kTwoPi * (Vec3d(no_sun.sky) + Vec3d(no_sun.ground))),
            1e-12);
}

TEST(SunSky, SunLandsInItsPixel) {
  const int r = 32;
  const CubemapLayout layout(r);
  // Pixels on several faces (near the +Y pole, on side faces, on the -Z seam, below the
  // horizon), with the sun a quarter pixel off centre.
  for (int k0 : {layout.index(2, 15, 16), layout.index(2, 6, 25), layout.index(4, 20, 9),
                 layout.index(0, 5, 12), layout.index(5, 16, 10), layout.index(1, 30, 2),
                 layout.index(3, 8, 8)}) {
    SunSky env;
    const Vec3d c = layout.direction(k0);
    const Vec3d tangent = glm::normalize(glm::cross(c, Vec3d(0.3, 0.5, 0.7)));
    const double size = std::sqrt(layout.solid_angle(k0));  // the pixel's angular size
    env.sun_dir = glm::normalize(c + 0.15 * size * tangent);
    env.sun_radius_rad = 0.3 * size;
    const Cubemap cube = resample_to_cubemap(env.to_latlong(512, 256, 4), r);
    const auto brightest = std::max_element(cube.radiance.begin(), cube.radiance.end(),
                                            [](const Rgb& a, const Rgb& b) { return a.x < b.x; });
    EXPECT_EQ(brightest - cube.radiance.begin(), layout.pixel_of(env.sun_dir)) << "pixel " << k0;
    EXPECT_EQ(layout.pixel_of(env.sun_dir), k0);
  }
}

TEST(SunSky, PointSampledCubemapAgreesAwayFromEdges) {
  SunSky env;
  const int r = 16;
  const Cubemap direct = env.to_cubemap(r);
  const Cubemap resampled = resample_to_cubemap(env.to_latlong(512, 256), r);
  const Vec3d sun = glm::normalize(env.sun_dir);
  int compared = 0;
  for (int k = 0; k < direct.layout.pixel_count(); ++k) {
    const Vec3d d = direct.layout.direction(k);
    // Skip pixels that may touch the horizon or the sun.
    if (std::abs(d.y) < 0.15 || angle_between(d, sun) < env.sun_radius_rad + 0.15) continue;
    ++compared;
    const Rgb expected = d.y > 0 ? env.sky : env.ground;
    for (int c = 0; c < 3; ++c) {
      ASSERT_NEAR(direct.radiance[k][c], expected[c], 1e-6) << k;
      ASSERT_NEAR(resampled.radiance[k][c], expected[c], 1e-5) << k;
    }
  }
  EXPECT_GT(compared, direct.layout.pixel_count() / 2);
}

// --- loading -------------------------------------------------------------------------------

TEST(LoadLatLong, InvalidTexelsZeroedWithOneWarning) {
  const fs::path dir = temp_dir("invalid");
  RgbImage img(16, 8);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 16; ++x) img.at(x, y) = Rgb(0.5f + x, 1.0f + y, 0.25f);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  img.at(0, 0) = Rgb(nan, 1.f, 1.f);
  img.at(3, 2) = Rgb(1.f, inf, -inf);  // two bad channels, one texel
  img.at(7, 7) = Rgb(1.f, 2.f, -0.5f);
  img.at(15, 4) = Rgb(nan, nan, nan);
  const fs::path file = dir / "bad.exr";
  write_exr(img, file);

  const int warnings_before = warning_count();
  EnvLoadReport report;
  const LatLongImage env = load_latlong_exr(file, &report);
  EXPECT_EQ(warning_count() - warnings_before, 1);
  EXPECT_EQ(report.invalid_texels, 4u);
  EXPECT_EQ(env.at(0, 0), Rgb(0.f, 1.f, 1.f));
  EXPECT_EQ(env.at(3, 2), Rgb(1.f, 0.f, 0.f));
  EXPECT_EQ(env.at(7, 7), Rgb(1.f, 2.f, 0.f));
  EXPECT_EQ(env.at(15, 4), Rgb(0.f));
  EXPECT_EQ(env.at(5, 5), img.at(5, 5));

  // A clean file: no warning, zero count.
  img.at(0, 0) = img.at(3, 2) = img.at(7, 7) = img.at(15, 4) = Rgb(1.f);
  write_exr(img, file);
  const int w2 = warning_count();
  load_latlong_exr(file, &report);
  EXPECT_EQ(warning_count(), w2);
  EXPECT_EQ(report.invalid_texels, 0u);
  fs::remove_all(dir);
}

void expect_input_error_naming(const fs::path& file, const std::string& why) {
  try {
    load_latlong_exr(file);
    ADD_FAILURE() << why << ": no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos)
        << why << ": " << e.what();
    EXPECT_EQ(e.file(), file);
  } catch (const std::exception& e) {
    ADD_FAILURE() << why << ": wrong exception type: " << e.what();
  }
}

TEST(LoadLatLong, BadInputsAreInputErrorsNamingTheFile) {
  const fs::path dir = temp_dir("bad");
  expect_input_error_naming(dir / "does_not_exist.exr", "missing file");

  std::mt19937_64 rng(kSeed);
  std::string noise(4096, '\0');
  for (char& ch : noise) ch = static_cast<char>(rng());
  { std::ofstream(dir / "noise.exr", std::ios::binary) << noise; }
  expect_input_error_naming(dir / "noise.exr", "random bytes");
  { std::ofstream(dir / "empty.exr", std::ios::binary); }
  expect_input_error_naming(dir / "empty.exr", "empty file");
  expect_input_error_naming(dir, "a directory");

  // A valid EXR cut in half.
  RgbImage img(64, 32);
  for (std::size_t i = 0; i < img.pixels.size(); ++i)
    img.pixels[i] = Rgb(float(rng() % 1000) / 7.f);
  write_exr(img, dir / "whole.exr");
  std::string bytes;
  {
    std::ifstream in(dir / "whole.exr", std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  ASSERT_GT(bytes.size(), 1000u);
  ASSERT_NO_THROW(load_latlong_exr(dir / "whole.exr"));
  for (std::size_t keep :
       {bytes.size() / 2, bytes.size() - 10, std::size_t{200}, std::size_t{20}}) {
    const fs::path cut = dir / ("cut_" + std::to_string(keep) + ".exr");
    std::ofstream(cut, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(keep));
    expect_input_error_naming(cut, "truncated to " + std::to_string(keep) + " bytes");
  }

  // No colour channels: rename R, G, B in the header's channel list to U, V, W (still sorted,
  // still a valid file, but nothing we can read as colour).
  const std::string tag = std::string("channels") + '\0' + "chlist" + '\0';
  const std::size_t at = bytes.find(tag);
  ASSERT_NE(at, std::string::npos);
  std::string renamed = bytes;
  std::size_t p = at + tag.size() + 4;  // skip the attribute size
  for (char to : {'U', 'V', 'W'}) {
    ASSERT_EQ(renamed[p + 1], '\0');
    renamed[p] = to;
    p += 2 + 16;  // name, NUL, pixel type + pLinear + reserved + x/y sampling
  }
  { std::ofstream(dir / "uvw.exr", std::ios::binary) << renamed; }
  try {
    load_latlong_exr(dir / "uvw.exr");
    ADD_FAILURE() << "no exception for an EXR without colour channels";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find((dir / "uvw.exr").string()), std::string::npos) << what;
    EXPECT_NE(what.find("U, V, W"), std::string::npos) << what;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace prt
