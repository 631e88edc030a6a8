// Image output: bit-exact float EXR round trips, PNG size and tone mapping, and the cubemap
// cross / strip layouts (adjacent faces must share their edges).
#include "prtlab/image/image_io.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>

#include "prtlab/base/error.h"
#include "support/refused_within_memory.h"

#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#include <stb/stb_image.h>

namespace prt {
namespace {

namespace fs = std::filesystem;
constexpr std::uint64_t kSeed = 20240603;

fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("prtlab_image_io_test_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

struct Png {
  int width = 0, height = 0, channels = 0;
  std::vector<unsigned char> rgb;
  unsigned char at(int x, int y, int c) const {
    return rgb[(static_cast<std::size_t>(y) * width + x) * 3 + c];
  }
};

Png read_png(const fs::path& file) {
  Png png;
  unsigned char* data = stbi_load(file.c_str(), &png.width, &png.height, &png.channels, 3);
  if (!data) return png;
  png.rgb.assign(data, data + static_cast<std::size_t>(png.width) * png.height * 3);
  stbi_image_free(data);
  return png;
}

TEST(Exr, FloatRoundTripIsBitExact) {
  const fs::path dir = temp_dir("exr");
  std::mt19937_64 rng(kSeed);
  RgbImage img(37, 23);  // odd sizes: no accidental alignment
  for (Rgb& p : img.pixels) {
    for (int c = 0; c < 3; ++c) p[c] = std::bit_cast<float>(static_cast<std::uint32_t>(rng()));
  }
  // Values a half-float path would lose, and the special ones.
  img.at(0, 0) = Rgb(1.0f + 1e-7f, 1e-40f /* denormal */, 3.0e38f);
  img.at(1, 0) = Rgb(-0.0f, std::numeric_limits<float>::infinity(), -2.5e-20f);
  img.at(2, 0) = Rgb(std::numeric_limits<float>::quiet_NaN(), 65504.5f, 0.1f);
  write_exr(img, dir / "a.exr");
  const RgbImage back = read_exr(dir / "a.exr");
  ASSERT_EQ(back.width, img.width);
  ASSERT_EQ(back.height, img.height);
  ASSERT_EQ(back.pixels.size(), img.pixels.size());
  EXPECT_EQ(std::memcmp(back.pixels.data(), img.pixels.data(), img.pixels.size() * sizeof(Rgb)), 0);
  // Atomic write: no temporary left behind.
  int files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 1);
  fs::remove_all(dir);
}

TEST(Exr, ErrorsNameTheFile) {
  const fs::path dir = temp_dir("exr_errors");
  try {
    read_exr(dir / "missing.exr");
    ADD_FAILURE() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("missing.exr"), std::string::npos);
  }
  RgbImage img(4, 4);
  // A path below a regular file cannot be created.
  write_exr(img, dir / "file.exr");
  EXPECT_THROW(write_exr(img, dir / "file.exr" / "sub.exr"), InputError);
  EXPECT_THROW(write_exr(RgbImage{}, dir / "empty.exr"), ParameterError);
  fs::remove_all(dir);
}

// Reading decodes in strips of rows: a tall image (several strips, the last one partial) comes
// back bit for bit, tiled or not.
TEST(Exr, ImagesOfManyStripsRoundTrip) {
  const fs::path dir = temp_dir("exr_strips");
  RgbImage img(19, 150);
  for (std::size_t i = 0; i < img.pixels.size(); ++i)
    img.pixels[i] = Rgb(static_cast<float>(i), 0.5f * static_cast<float>(i % 7), -1.0f);
  write_exr(img, dir / "tall.exr");
  const RgbImage back = read_exr(dir / "tall.exr");
  ASSERT_EQ(back.pixels.size(), img.pixels.size());
  EXPECT_EQ(std::memcmp(back.pixels.data(), img.pixels.data(), img.pixels.size() * sizeof(Rgb)), 0);
  fs::remove_all(dir);
}

// A header may declare any size. A file of a few KB declaring 20000 x 10000 pixels (2.4 GB as
// float RGB) must fail without touching memory of that size: measured as the peak resident size
// of a child process that reads it.
TEST(Exr, AHeaderDeclaringAHugeImageFailsWithoutAllocatingIt) {
  const fs::path dir = temp_dir("exr_huge");
  write_exr(RgbImage(64, 32), dir / "small.exr");
  std::string bytes;
  {
    std::ifstream in(dir / "small.exr", std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const std::string key("dataWindow\0box2i\0", 17);
  const auto at = bytes.find(key);
  ASSERT_NE(at, std::string::npos);
  const std::int32_t window[4] = {0, 0, 19999, 9999};
  std::memcpy(bytes.data() + at + key.size() + 4, window, sizeof(window));
  std::ofstream(dir / "huge.exr", std::ios::binary) << bytes;

  EXPECT_TRUE(prt::testing::refused_within_memory([&] { (void)read_exr(dir / "huge.exr"); }, 512));
  fs::remove_all(dir);
}

TEST(Png, WrittenWithTheRightSizeAndToneMap) {
  const fs::path dir = temp_dir("png");
  RgbImage img(40, 25);
  for (Rgb& p : img.pixels) p = Rgb(4.0f);
  img.at(3, 4) = Rgb(4.0f, 0.0f, 0.0f);
  const fs::path file = dir / "a.png";
  write_png(img, file);
  ASSERT_TRUE(fs::exists(file));
  EXPECT_GT(fs::file_size(file), 0u);
  const Png png = read_png(file);
  ASSERT_EQ(png.width, 40);
  ASSERT_EQ(png.height, 25);
  // Auto exposure maps the 99th-percentile luminance (4.0) to 0.9; gamma 2.2 gives 0.9^(1/2.2).
  const int grey = static_cast<int>(std::lround(std::pow(0.9, 1 / 2.2) * 255));
  EXPECT_NEAR(png.at(0, 0, 0), grey, 1);
  EXPECT_NEAR(png.at(39, 24, 2), grey, 1);
  EXPECT_NEAR(png.at(3, 4, 0), grey, 1);  // the red pixel: same red, no green
  EXPECT_EQ(png.at(3, 4, 1), 0);

  // Fixed exposure, no auto: 0.25 * 2^1 = 0.5 -> 0.5^(1/2.2); Reinhard: 0.5 / 1.5.
  ToneMap tm;
  tm.auto_exposure = false;
  tm.exposure = 1.0;
  for (Rgb& p : img.pixels) p = Rgb(0.25f);
  write_png(img, file, tm);
  EXPECT_NEAR(read_png(file).at(10, 10, 1), std::lround(std::pow(0.5, 1 / 2.2) * 255), 1);
  tm.reinhard = true;
  write_png(img, file, tm);
  EXPECT_NEAR(read_png(file).at(10, 10, 1), std::lround(std::pow(0.5 / 1.5, 1 / 2.2) * 255), 1);
  // Non-finite and negative values do not poison the image.
  img.at(0, 0) =
      Rgb(std::numeric_limits<float>::quiet_NaN(), -1.f, std::numeric_limits<float>::infinity());
  write_png(img, file);
  const Png odd = read_png(file);
  EXPECT_EQ(odd.at(0, 0, 0), 0);
  EXPECT_EQ(odd.at(0, 0, 1), 0);
  EXPECT_NEAR(odd.at(5, 5, 0), grey, 1);
  fs::remove_all(dir);
}

// Radiance = the pixel's direction, so the images can be decoded back to directions.
Cubemap direction_cubemap(int r) {
  Cubemap c(r);
  for (int k = 0; k < c.layout.pixel_count(); ++k) c.radiance[k] = Rgb(c.layout.direction(k));
  return c;
}

double angle_between(const Vec3d& a, const Vec3d& b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

TEST(Cross, FacesAreWhereDocumentedAndNeighboursMeet) {
  const int r = 8;
  const Cubemap cube = direction_cubemap(r);
  const RgbImage cross = cubemap_cross_image(cube);
  ASSERT_EQ(cross.width, 4 * r);
  ASSERT_EQ(cross.height, 3 * r);
  // Cell centres point along the documented axes.
  auto cell_dir = [&](int cx, int cy) {
    const Rgb a = cross.at(cx * r + r / 2 - 1, cy * r + r / 2 - 1),
              b = cross.at(cx * r + r / 2, cy * r + r / 2);
    return glm::normalize(Vec3d(a) + Vec3d(b));
  };
  auto near = [](const Vec3d& a, const Vec3d& b) { return glm::length(a - b) < 1e-6; };
  EXPECT_TRUE(near(cell_dir(1, 0), {0, 1, 0}));  // +Y on top
  EXPECT_TRUE(near(cell_dir(0, 1), {-1, 0, 0}));
  EXPECT_TRUE(near(cell_dir(1, 1), {0, 0, 1}));
  EXPECT_TRUE(near(cell_dir(2, 1), {1, 0, 0}));
  EXPECT_TRUE(near(cell_dir(3, 1), {0, 0, -1}));
  EXPECT_TRUE(near(cell_dir(1, 2), {0, -1, 0}));
  // Unused cells are black.
  EXPECT_EQ(cross.at(0, 0), Rgb(0.f));
  EXPECT_EQ(cross.at(4 * r - 1, 3 * r - 1), Rgb(0.f));

  // Every pair of horizontally or vertically adjacent used pixels (within a face or across a
  // face edge in the cross) must be neighbours on the sphere; this fails for any face placed
  // rotated or mirrored. The middle row also wraps around (-Z's right edge meets -X's left).
  auto used = [&](int x, int y) { return cross.at(x, y) != Rgb(0.f); };
  const double limit = 1.5 * (2.0 / r);  // a pixel step is at most 2/R radians
  int pairs = 0;
  for (int y = 0; y < 3 * r; ++y) {
    for (int x = 0; x < 4 * r; ++x) {
      if (!used(x, y)) continue;
      const bool wrap = x == 4 * r - 1 && y >= r && y < 2 * r;
      const int xr = wrap ? 0 : x + 1;
      for (auto [nx, ny] : {std::pair{xr, y}, std::pair{x, y + 1}}) {
        if (nx >= 4 * r || ny >= 3 * r || !used(nx, ny)) continue;
        ++pairs;
        ASSERT_LT(angle_between(Vec3d(cross.at(x, y)), Vec3d(cross.at(nx, ny))), limit)
            << "pixels (" << x << "," << y << ") and (" << nx << "," << ny
            << ") are not neighbours";
      }
    }
  }
  EXPECT_EQ(pairs, 6 * 2 * r * (r - 1) + 4 * r /* middle row seams */ + 2 * r /* +Y, -Y */);
}

TEST(Strip, RoundTripThroughExr) {
  const fs::path dir = temp_dir("strip");
  const Cubemap cube = direction_cubemap(5);
  const RgbImage strip = cubemap_strip_image(cube);
  ASSERT_EQ(strip.width, 30);
  ASSERT_EQ(strip.height, 5);
  EXPECT_EQ(strip.at(2 * 5 + 2, 2), cube.radiance[cube.layout.index(2, 2, 2)]);
  write_exr(strip, dir / "strip.exr");
  const Cubemap back = cubemap_from_strip_image(read_exr(dir / "strip.exr"), dir / "strip.exr");
  EXPECT_EQ(back.radiance, cube.radiance);
  EXPECT_THROW(cubemap_from_strip_image(RgbImage(10, 5), "x.exr"), InputError);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace prt
