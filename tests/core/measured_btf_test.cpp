// Measured BTFs (UTIA image directories, Bonn UBO files): writer -> reader round trips, files
// built byte by byte that decode to known values, nearest-direction resampling when the
// measured directions are not the grid's, and bad files reported as InputError naming them.
#include "prtlab/btf/measured_btf.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/btf/btf.h"
#include "prtlab/btf/ubo_btf.h"
#include "prtlab/btf/utia_btf.h"
#include "prtlab/image/image_io.h"
#include "prtlab/numeric/float16.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "support/cli_runner.h"
#include "support/refused_within_memory.h"
#include "support/temp_dir.h"

// The largest single allocation since the last reset, so that a test can show that a reader
// refuses a file without first allocating what the file's header asks for.
namespace {
std::atomic<std::size_t> g_largest_allocation{0};
}  // namespace

// Out of line, so that the compiler does not pair an inlined malloc with an inlined free.
[[gnu::noinline]] void* operator new(std::size_t n) {
  std::size_t seen = g_largest_allocation.load(std::memory_order_relaxed);
  while (n > seen &&
         !g_largest_allocation.compare_exchange_weak(seen, n, std::memory_order_relaxed)) {
  }
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
[[gnu::noinline]] void operator delete(void* p) noexcept {
  std::free(p);
}
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}

namespace prt {
namespace {

namespace fs = std::filesystem;
using prt::testing::TempDir;

constexpr double kDeg = kPi / 180.0;

// Values in (0, 1]; with `half_exact` multiples of 1/1024, which binary16 holds exactly.
Btf random_btf(int u, int view_side, int light_side, std::uint64_t seed, bool half_exact = false) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> q(1, 1024);
  std::uniform_real_distribution<float> r(0.001f, 1.0f);
  const std::size_t n =
      static_cast<std::size_t>(u) * u * view_side * view_side * light_side * light_side * 3;
  std::vector<float> rgb(n);
  for (float& v : rgb) v = half_exact ? static_cast<float>(q(rng)) / 1024.0f : r(rng);
  return Btf("random", u, view_side, light_side, std::move(rgb));
}

bool bitwise_equal(const Btf& a, const Btf& b) {
  return a.resolution() == b.resolution() && a.view_side() == b.view_side() &&
         a.light_side() == b.light_side() && a.bytes() == b.bytes() &&
         std::memcmp(a.data().data(), b.data().data(), a.bytes()) == 0;
}

// Largest |a - b| / max(|a|, tiny) over all values.
double max_relative_error(const Btf& a, const Btf& b) {
  EXPECT_EQ(a.value_count(), b.value_count());
  double worst = 0;
  for (std::size_t i = 0; i < std::min(a.value_count(), b.value_count()); ++i) {
    const double x = a.data()[i], y = b.data()[i];
    worst = std::max(worst, std::abs(x - y) / std::max(std::abs(x), 1e-30));
  }
  return worst;
}

double max_abs_error(const Btf& a, const Btf& b) {
  double worst = 0;
  for (std::size_t i = 0; i < std::min(a.value_count(), b.value_count()); ++i)
    worst = std::max(worst, std::abs(static_cast<double>(a.data()[i]) - b.data()[i]));
  return worst;
}

MeasuredImportOptions grid_of(const Btf& b, LightCosine cosine) {
  MeasuredImportOptions o;
  o.view_side = b.view_side();
  o.light_side = b.light_side();
  o.cosine = cosine;
  return o;
}

MeasuredImportOptions zenith_only(LightCosine cosine = LightCosine::kAsStored) {
  MeasuredImportOptions o;
  o.view_side = 1;
  o.light_side = 1;
  o.cosine = cosine;
  return o;
}

// Asserts that `f` throws InputError whose file is `file`.
template <class F>
void expect_input_error(F&& f, const fs::path& file, const std::string& contains = {}) {
  try {
    f();
    ADD_FAILURE() << "no InputError for " << file;
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), file) << e.what();
    if (!contains.empty()) {
      EXPECT_NE(std::string(e.what()).find(contains), std::string::npos) << e.what();
    }
  }
}

// --- names ----------------------------------------------------------------------------------

TEST(UtiaNames, ParseAndFormat) {
  const auto a = parse_utia_image_name("tl015_pl000_tv030_pv060.png");
  ASSERT_TRUE(a);
  EXPECT_EQ(a->theta_light, 15);
  EXPECT_EQ(a->phi_light, 0);
  EXPECT_EQ(a->theta_view, 30);
  EXPECT_EQ(a->phi_view, 60);
  const auto d = parse_utia_image_name("TL7.5_PL359.25_TV0_PV0.EXR");
  ASSERT_TRUE(d);
  EXPECT_EQ(d->theta_light, 7.5);
  EXPECT_EQ(d->phi_light, 359.25);
  for (const char* bad :
       {"tl015_pl000_tv030_pv060.jpg", "tl015_pl000_tv030.png", "tl091_pl000_tv030_pv060.png",
        "tl015_pl360_tv030_pv060.png", "tl1._pl0_tv0_pv0.png", "xtl015_pl000_tv030_pv060.png",
        "tl-15_pl000_tv030_pv060.png"})
    EXPECT_FALSE(parse_utia_image_name(bad)) << bad;
  EXPECT_EQ(utia_image_name({15.4, 359.6, 30, -10}, "exr"), "tl015_pl000_tv030_pv350.exr");
}

// --- UTIA round trips -----------------------------------------------------------------------

TEST(UtiaBtf, ExrRoundTripIsBitwise) {
  TempDir dir("utia");
  const Btf b = random_btf(4, 3, 2, 1);
  UtiaWriteOptions w;
  w.cosine = LightCosine::kAsStored;
  const UtiaWriteReport report = write_utia_btf(b, dir / "out", w);
  EXPECT_EQ(report.images, 9 * 4);
  EXPECT_TRUE(fs::exists(dir / "out" / "tl041_pl225_tv000_pv000.exr"));
  const MeasuredBtf m = read_utia_btf(dir / "out", grid_of(b, LightCosine::kAsStored));
  EXPECT_TRUE(bitwise_equal(m.btf, b));
  EXPECT_EQ(m.coverage.measured_views, 9);
  EXPECT_EQ(m.coverage.measured_lights, 4);
  EXPECT_EQ(m.coverage.views_used, 9);
  EXPECT_EQ(m.coverage.lights_used, 4);
  // The names round the angles to whole degrees; nothing else moves the directions.
  EXPECT_LT(m.coverage.max_view_angle_deg, 0.71);
  EXPECT_LT(m.coverage.max_light_angle_deg, 0.71);
  EXPECT_EQ(m.btf.material(), "utia:out");
}

TEST(UtiaBtf, CellMeanCosineRoundTripWithinRounding) {
  TempDir dir("utia");
  const Btf b = random_btf(4, 2, 3, 2);
  write_utia_btf(b, dir / "out");
  const MeasuredBtf m = read_utia_btf(dir / "out", grid_of(b, LightCosine::kCellMean));
  EXPECT_LT(max_relative_error(m.btf, b), 3e-7);
  // The images themselves hold b * cos(theta_named) / c_j: the zenith light of an odd grid.
  const HemisphereGrid lights(3);
  const double c4 = lights.projected_solid_angles()[4] / lights.cell_solid_angle();
  const RgbImage img = read_exr(dir / "out" / "tl000_pl000_tv041_pv225.exr");
  EXPECT_NEAR(img.at(0, 3).r, b.value(0, 0, 4).r / c4, 1e-6);
}

TEST(UtiaBtf, Png16WithinQuantisationStep) {
  TempDir dir("utia");
  const Btf b = random_btf(4, 2, 2, 3);
  UtiaWriteOptions w;
  w.format = UtiaImageFormat::kPng16;
  w.cosine = LightCosine::kAsStored;
  w.png_scale = 2.0;
  const UtiaWriteReport report = write_utia_btf(b, dir / "out", w);
  EXPECT_EQ(report.clipped, 0u);
  MeasuredImportOptions o = grid_of(b, LightCosine::kAsStored);
  o.scale = 2.0;
  const MeasuredBtf m = read_utia_btf(dir / "out", o);
  const double step = 2.0 / 65535;
  EXPECT_LE(max_abs_error(m.btf, b), 0.5 * step * (1 + 1e-6));
  EXPECT_GT(max_abs_error(m.btf, b), 0.0);  // it is really quantised
}

TEST(UtiaBtf, BoxFilterAveragesTexels) {
  TempDir dir("utia");
  const Btf b = random_btf(4, 1, 1, 4);
  UtiaWriteOptions w;
  w.cosine = LightCosine::kAsStored;
  write_utia_btf(b, dir / "out", w);
  MeasuredImportOptions o = grid_of(b, LightCosine::kAsStored);
  o.resolution = 2;
  const MeasuredBtf m = read_utia_btf(dir / "out", o);
  ASSERT_EQ(m.btf.resolution(), 2);
  EXPECT_EQ(m.coverage.box_factor, 2);
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 2; ++x) {
      Rgb sum(0.f);
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) sum += b.value((2 * y + dy) * 4 + 2 * x + dx, 0, 0);
      const Rgb got = m.btf.value(y * 2 + x, 0, 0);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], sum[c] / 4, 1e-6);
    }
  }
  o.resolution = 3;
  EXPECT_THROW(read_utia_btf(dir / "out", o), ParameterError);
}

// --- nearest directions ---------------------------------------------------------------------

RgbImage constant_image(int size, float value) {
  RgbImage img(size, size);
  for (Rgb& p : img.pixels) p = Rgb(value, 2 * value, 3 * value);
  return img;
}

TEST(UtiaBtf, NearestMeasuredDirectionIsTaken) {
  TempDir dir("utia");
  // Light grid side 2: cell j = row * 2 + col has its centre at theta 41.4 deg and phi 225
  // (j = 0), 315 (1), 135 (2), 45 (3). The measured lights are near them but not on them,
  // and one low light near phi 45 must lose to the closer one.
  struct Light {
    double theta, phi;
  };
  const std::vector<Light> measured = {{40, 50}, {40, 130}, {45, 220}, {35, 320}, {80, 45}};
  const int expected_for_cell[4] = {2, 3, 1, 0};
  for (std::size_t l = 0; l < measured.size(); ++l) {
    for (double view_theta : {0.0, 70.0}) {
      const float id = static_cast<float>(l + 1) + (view_theta > 0 ? 100.f : 0.f);
      write_exr(constant_image(2, id),
                dir / utia_image_name({measured[l].theta, measured[l].phi, view_theta, 0}, "exr"));
    }
  }
  MeasuredImportOptions o;
  o.view_side = 1;
  o.light_side = 2;
  o.cosine = LightCosine::kAsStored;
  const MeasuredBtf m = read_utia_btf(dir.path(), o);
  const HemisphereGrid grid(2);
  double worst = 0;
  for (int j = 0; j < 4; ++j) {
    const int want = expected_for_cell[j];
    EXPECT_EQ(m.btf.value(0, 0, j).r, static_cast<float>(want + 1)) << "cell " << j;
    EXPECT_EQ(m.btf.value(3, 0, j).b, 3.f * static_cast<float>(want + 1));
    const Vec3d d = direction_from_angles(measured[want].theta * kDeg, measured[want].phi * kDeg);
    worst = std::max(worst, std::acos(glm::dot(d, grid.direction(j))) / kDeg);
  }
  EXPECT_EQ(m.coverage.lights_used, 4);
  EXPECT_EQ(m.coverage.views_used, 1);
  EXPECT_EQ(m.coverage.max_view_angle_deg, 0.0);
  EXPECT_NEAR(m.coverage.max_light_angle_deg, worst, 1e-9);
  EXPECT_GT(m.coverage.max_light_angle_deg, 5.0);
}

TEST(NearestDirections, MatchesBruteForceAndSkipsUnusable) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g;
  auto random_up = [&] {
    Vec3d d(g(rng), g(rng), std::abs(g(rng)));
    return glm::normalize(d);
  };
  std::vector<Vec3d> measured(40), grid = HemisphereGrid(5).directions();
  for (Vec3d& d : measured) d = random_up();
  std::vector<bool> usable(measured.size(), true);
  usable[3] = usable[17] = false;
  const NearestDirections n = nearest_directions(grid, measured, usable);
  for (std::size_t i = 0; i < grid.size(); ++i) {
    double best = 10;
    int arg = -1;
    for (std::size_t m = 0; m < measured.size(); ++m) {
      const double a = std::acos(std::clamp(glm::dot(grid[i], measured[m]), -1.0, 1.0));
      if (usable[m] && a < best) best = a, arg = static_cast<int>(m);
    }
    EXPECT_EQ(n.index[i], arg);
    EXPECT_NEAR(n.angle[i], best, 1e-12);
  }
}

// --- UTIA errors ----------------------------------------------------------------------------

TEST(UtiaBtf, BadDirectoriesNameTheFile) {
  TempDir dir("utia");
  const fs::path d = dir / "btf";
  fs::create_directories(d);
  expect_input_error([&] { read_utia_btf(d); }, d, "no .png or .exr");
  write_exr(constant_image(2, 1), d / "tl000_pl000_tv000_pv000.exr");
  write_exr(constant_image(2, 1), d / "tl000_pl000_tv030_pv000.exr");
  write_exr(constant_image(2, 1), d / "tl045_pl090_tv000_pv000.exr");
  // light (45, 90) x view (30, 0) is missing
  expect_input_error([&] { read_utia_btf(d); }, d / "tl045_pl090_tv030_pv000.png", "missing");
  write_exr(constant_image(4, 1), d / "tl045_pl090_tv030_pv000.exr");
  try {
    read_utia_btf(d);
    ADD_FAILURE() << "differently sized images accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("other images"), std::string::npos) << e.what();
  }
  RgbImage wide(4, 2);
  write_exr(wide, d / "tl045_pl090_tv030_pv000.exr");
  fs::remove(d / "tl000_pl000_tv000_pv000.exr");
  write_exr(wide, d / "tl000_pl000_tv000_pv000.exr");
  expect_input_error([&] { read_utia_btf(d); }, d / "tl000_pl000_tv000_pv000.exr", "square");
  write_exr(constant_image(2, 1), d / "tl000_pl000_tv000_pv000.exr");
  write_exr(constant_image(2, 1), d / "tl045_pl090_tv030_pv000.exr");
  EXPECT_NO_THROW(read_utia_btf(d));
  std::ofstream(d / "notes.txt") << "ignored";
  EXPECT_NO_THROW(read_utia_btf(d));
  std::ofstream(d / "tl000_pl000_tv000_pv000.png") << "not a png";
  expect_input_error([&] { read_utia_btf(d); }, d / "tl000_pl000_tv000_pv000.png", "same");
  fs::remove(d / "tl000_pl000_tv000_pv000.exr");
  expect_input_error([&] { read_utia_btf(d); }, d / "tl000_pl000_tv000_pv000.png", "PNG");
  std::ofstream(d / "light1_view2.png") << "x";
  expect_input_error([&] { read_utia_btf(d); }, d / "light1_view2.png", "does not match");
  expect_input_error([&] { read_utia_btf(d / "nope"); }, d / "nope", "not found");
  expect_input_error([&] { read_utia_btf(d / "notes.txt"); }, d / "notes.txt", "not a directory");
}

// A PNG whose header declares 100,000 x 100,000 pixels is named as too large (stb alone would
// say "unknown image type": it refuses the size, then tries its other formats).
TEST(UtiaBtf, APngDeclaringAnAbsurdSizeIsNamedAsTooLarge) {
  TempDir dir("utia");
  const fs::path d = dir / "btf";
  fs::create_directories(d);
  const fs::path png = d / "tl000_pl000_tv000_pv000.png";
  write_png(constant_image(2, 1), png);
  std::string bytes;
  {
    std::ifstream in(png, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  ASSERT_GT(bytes.size(), 24u);
  ASSERT_EQ(bytes.substr(12, 4), "IHDR");
  for (const int at : {16, 20}) {  // width and height, big-endian
    const std::uint32_t v = 100000;
    for (int k = 0; k < 4; ++k) bytes[at + k] = static_cast<char>((v >> (24 - 8 * k)) & 0xff);
  }
  std::ofstream(png, std::ios::binary) << bytes;
  try {
    (void)read_utia_btf(d);
    ADD_FAILURE() << "a 1e10-pixel PNG was read";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(png.filename().string()), std::string::npos) << what;
    EXPECT_NE(what.find("100000 x 100000"), std::string::npos) << what;
    EXPECT_NE(what.find("too large"), std::string::npos) << what;
    EXPECT_EQ(what.find("unknown image type"), std::string::npos) << what;
  }
}

TEST(UtiaBtf, NamesSharingNoAnglesNameTheMissingFileWithoutAnNSquaredTable) {
  TempDir dir("utia");
  const fs::path d = dir / "btf";
  fs::create_directories(d);
  // Three images of disjoint angles: 3 lights x 3 views in the names. The images are never
  // read (empty files): the missing pair is found from the names alone.
  for (const char* name : {"tl010_pl000_tv000_pv000.exr", "tl020_pl000_tv010_pv000.exr",
                           "tl030_pl000_tv020_pv000.exr"})
    std::ofstream(d / name) << "";
  expect_input_error([&] { read_utia_btf(d); }, d / "tl020_pl000_tv000_pv000.png",
                     "3 lights x 3 views in the names, 3 images");

  // 1000 such names: 10^6 pairs, which must not be allocated (32 MB of paths).
  const fs::path big = dir / "big";
  fs::create_directories(big);
  for (int i = 0; i < 1000; ++i)
    std::ofstream(big / fmt::format("tl45_pl{:.2f}_tv30_pv{:.2f}.exr", 0.25 * i, 0.25 * i)) << "";
  g_largest_allocation = 0;
  expect_input_error([&] { read_utia_btf(big); }, big / "tl045_pl0.25_tv030_pv000.png",
                     "1000 lights x 1000 views");
  EXPECT_LT(g_largest_allocation.load(), std::size_t{1} << 20);
}

TEST(UtiaBtf, NonFiniteValuesAreInputErrorsNamingThem) {
  TempDir dir("utia");
  for (float bad : {std::nanf(""), -std::numeric_limits<float>::infinity()}) {
    const fs::path d = dir / (std::isnan(bad) ? "nan" : "inf");
    fs::create_directories(d);
    RgbImage img = constant_image(2, 0.5f);
    img.at(1, 0).g = bad;  // row 0 is texel y = 1
    write_exr(img, d / "tl000_pl000_tv000_pv000.exr");
    expect_input_error([&] { read_utia_btf(d, zenith_only()); }, d / "tl000_pl000_tv000_pv000.exr",
                       fmt::format("texel (1, 1) channel G is {}", bad));
  }
}

TEST(UtiaBtf, NegativeValuesAreClampedAndCounted) {
  TempDir dir("utia");
  RgbImage img = constant_image(2, 0.5f);
  img.at(0, 0).r = -0.25f;
  img.at(1, 1).b = -1e-3f;
  write_exr(img, dir / "tl000_pl000_tv000_pv000.exr");
  const int warnings = warning_count();
  const MeasuredBtf m = read_utia_btf(dir.path(), zenith_only());
  EXPECT_EQ(m.coverage.negative_clamped, 2u);
  EXPECT_EQ(m.coverage.values_checked, 12u);
  EXPECT_EQ(m.coverage.to_json().at("negative_clamped"), 2);
  EXPECT_EQ(m.btf.parameters().at("measured").at("negative_clamped"), 2);
  EXPECT_EQ(warning_count(), warnings + 1);
  EXPECT_EQ(m.btf.value(2, 0, 0).r, 0.f);  // pixel (0, 0) is texel (0, 1)
  EXPECT_EQ(m.btf.value(1, 0, 0).b, 0.f);  // pixel (1, 1) is texel (1, 0)
  EXPECT_EQ(m.btf.value(1, 0, 0).r, 0.5f);
  // A measurement without negative values warns about nothing.
  write_exr(constant_image(2, 0.5f), dir / "tl000_pl000_tv000_pv000.exr");
  EXPECT_EQ(read_utia_btf(dir.path(), zenith_only()).coverage.negative_clamped, 0u);
  EXPECT_EQ(warning_count(), warnings + 1);
}

TEST(UtiaBtf, WriterRefusesNonEmptyDirectory) {
  TempDir dir("utia");
  std::ofstream(dir / "x") << "x";
  EXPECT_THROW(write_utia_btf(random_btf(2, 1, 1, 5), dir.path()), ParameterError);
}

// --- UBO round trips ------------------------------------------------------------------------

TEST(UboBtf, FmfExactRoundTripIsBitwise) {
  TempDir dir("ubo");
  for (int u : {2, 4}) {  // texels fewer and more than the 3 V M angular rows
    const Btf b = random_btf(u, 2, 1, 10 + u);
    UboWriteOptions w;
    w.cosine = LightCosine::kAsStored;
    const fs::path file = dir / fmt::format("u{}.btf", u);
    write_ubo_fmf(b, file, w);
    EXPECT_EQ(ubo_btf_format(file), "FMF");
    const MeasuredBtf m = read_ubo_btf(file, grid_of(b, LightCosine::kAsStored));
    EXPECT_TRUE(bitwise_equal(m.btf, b)) << "U = " << u;
    EXPECT_LT(m.coverage.max_view_angle_deg, 1e-4);
    EXPECT_EQ(m.btf.material(), fmt::format("ubo:u{}", u));
  }
}

TEST(UboBtf, FmfCellMeanHalfAndTruncatedRoundTrips) {
  TempDir dir("ubo");
  const Btf b = random_btf(3, 2, 2, 20);
  write_ubo_fmf(b, dir / "cell.btf");
  EXPECT_LT(
      max_relative_error(read_ubo_btf(dir / "cell.btf", grid_of(b, LightCosine::kCellMean)).btf, b),
      3e-7);
  UboWriteOptions half;
  half.scalar_bytes = 2;
  write_ubo_fmf(b, dir / "half.btf", half);
  EXPECT_LT(
      max_relative_error(read_ubo_btf(dir / "half.btf", grid_of(b, LightCosine::kCellMean)).btf, b),
      1.5 / 2048);
  UboWriteOptions svd;
  svd.components = 9;  // full rank of the 48 x 9 matrix
  write_ubo_fmf(b, dir / "svd.btf", svd);
  EXPECT_LT(max_abs_error(read_ubo_btf(dir / "svd.btf", grid_of(b, LightCosine::kCellMean)).btf, b),
            1e-5);
  svd.components = 2;
  write_ubo_fmf(b, dir / "svd2.btf", svd);
  const double truncated =
      max_abs_error(read_ubo_btf(dir / "svd2.btf", grid_of(b, LightCosine::kCellMean)).btf, b);
  EXPECT_GT(truncated, 1e-3);  // random data is not rank 2
  svd.components = 10;
  EXPECT_THROW(write_ubo_fmf(b, dir / "bad.btf", svd), ParameterError);
}

TEST(UboBtf, BdiRoundTripIsBitwiseForHalfValues) {
  TempDir dir("ubo");
  const Btf b = random_btf(4, 2, 2, 30, /*half_exact=*/true);
  UboWriteOptions w;
  w.cosine = LightCosine::kAsStored;
  w.scan_lines_per_chunk = 3;  // a short last chunk
  write_ubo_bdi(b, dir / "b.bdi", w);
  EXPECT_EQ(ubo_btf_format(dir / "b.bdi"), "BDI");
  EXPECT_TRUE(
      bitwise_equal(read_ubo_btf(dir / "b.bdi", grid_of(b, LightCosine::kAsStored)).btf, b));
  write_ubo_bdi(b, dir / "c.bdi");
  EXPECT_LT(
      max_relative_error(read_ubo_btf(dir / "c.bdi", grid_of(b, LightCosine::kCellMean)).btf, b),
      1.0 / 2048);
}

// --- UBO files built byte by byte -----------------------------------------------------------

struct Bytes {
  std::string s;
  void u8(int v) { s.push_back(static_cast<char>(v)); }
  void u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) s.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
  }
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void f32(float v) {
    std::uint32_t bits;
    std::memcpy(&bits, &v, 4);
    u32(bits);
  }
  void half(float v) {
    const std::uint16_t h = float_to_half(v);
    u8(h & 0xFF);
    u8(h >> 8);
  }
  void text(const std::string& t) { s += t; }
  void save(const fs::path& p) const { std::ofstream(p, std::ios::binary) << s; }
};

struct Angles {
  float theta, phi;  // degrees
};

// Signature, meta data (version 1, or 2 with the cosine flag) and a sampling of the same
// lights for every view, and the texture extent.
void common_header(Bytes& b, const std::string& signature, const std::vector<Angles>& views,
                   const std::vector<Angles>& lights, int width, int height, int cosine = -1) {
  b.text(signature);
  b.u32(cosine < 0 ? 4 + 4 + 240 + 4 + 12 : 4 + 4 + 240 + 4 + 12 + 4);
  b.u32(cosine < 0 ? 1 : 2);
  b.text(std::string(240, '\0'));
  b.f32(10.f);
  for (int c = 0; c < 3; ++c) b.f32(1.f);
  if (cosine >= 0) b.u32(static_cast<std::uint32_t>(cosine));
  b.u32(static_cast<std::uint32_t>(views.size()));
  for (const Angles& v : views) {
    b.f32(static_cast<float>(v.theta * kDeg));
    b.f32(static_cast<float>(v.phi * kDeg));
    b.u32(static_cast<std::uint32_t>(lights.size()));
    for (const Angles& l : lights) {
      b.f32(static_cast<float>(l.theta * kDeg));
      b.f32(static_cast<float>(l.phi * kDeg));
    }
  }
  b.u32(static_cast<std::uint32_t>(width));
  b.u32(static_cast<std::uint32_t>(height));
}

// "!FMF06FC": no header version, no rotations. 2 x 2 texels, views {0, 60 deg}, lights
// {0, 45 deg}, one component: U[r] = r + 1 with r = c + 3 (l + 2 v), SxV[t] = (t + 1) / 2.
Bytes hand_fmf() {
  Bytes b;
  common_header(b, "!FMF06FC", {{0, 0}, {60, 0}}, {{0, 0}, {45, 90}}, 2, 2);
  b.u32(1);
  b.u8(4);
  b.u32(1);
  b.u32(12);
  b.u32(4);
  b.f32(1.f);
  for (int r = 0; r < 12; ++r) b.f32(static_cast<float>(r + 1));
  for (int t = 0; t < 4; ++t) b.f32(0.5f * static_cast<float>(t + 1));
  return b;
}

TEST(UboBtf, HandBuiltFmfDecodes) {
  TempDir dir("ubo");
  hand_fmf().save(dir / "a.btf");
  // The zenith view and light are view 0 and light 0: rows r = c.
  const MeasuredBtf m = read_ubo_btf(dir / "a.btf", zenith_only());
  for (int t = 0; t < 4; ++t)
    for (int c = 0; c < 3; ++c)
      EXPECT_FLOAT_EQ(m.btf.value(t, 0, 0)[c], (c + 1) * 0.5f * (t + 1)) << t << " " << c;
  // cell-mean: the data has no cosine, so the value is multiplied by c_0 = pi / (2 pi).
  const MeasuredBtf cm = read_ubo_btf(dir / "a.btf", zenith_only(LightCosine::kCellMean));
  EXPECT_FLOAT_EQ(cm.btf.value(3, 0, 0).b, 3 * 0.5f * 4 * 0.5f);
  EXPECT_EQ(cm.btf.material(), "ubo:a");
}

TEST(UboBtf, HandBuiltFmfWithImageRowsAndCosineFlag) {
  TempDir dir("ubo");
  // "!FMF12FCER" with rotations and header version 1 (log dynamic range), U holding the
  // texel rows (r = c + 3 t) and SxV the angular ones (s = l + nL v). Lights at 45 and 60 deg
  // only: the zenith cell takes the 45-degree light (s = 0 for view 0), whose cosine the
  // flag says is in the data.
  Bytes b;
  common_header(b, "!FMF12FCER", {{0, 0}}, {{45, 0}, {60, 180}}, 1, 1, /*cosine=*/1);
  b.u32(1);  // one rotation, skipped
  for (int i = 0; i < 9; ++i) b.f32(i == 0 || i == 4 || i == 8 ? 1.f : 0.f);
  b.u8(1);
  b.u32(1);  // log dynamic range
  b.u32(1);
  b.u8(4);
  b.u32(1);
  b.u32(3);  // 3 channels x 1 texel
  b.u32(2);  // 2 lights x 1 view
  b.f32(1.f);
  for (float v : {0.1f, 0.2f, 0.3f}) b.f32(v);
  for (float v : {2.f, 5.f}) b.f32(v);
  b.save(dir / "b.btf");
  const MeasuredBtf raw = read_ubo_btf(dir / "b.btf", zenith_only());
  const MeasuredBtf cell = read_ubo_btf(dir / "b.btf", zenith_only(LightCosine::kCellMean));
  for (int c = 0; c < 3; ++c) {
    const double stored = std::exp(0.1 * (c + 1) * 2.0) - 1e-5;
    EXPECT_NEAR(raw.btf.value(0, 0, 0)[c], stored, 1e-6);
    EXPECT_NEAR(cell.btf.value(0, 0, 0)[c], stored / std::cos(45 * kDeg) * 0.5, 1e-6);
  }
  EXPECT_NEAR(raw.coverage.max_light_angle_deg, 45.0, 1e-4);
}

TEST(UboBtf, HandBuiltDfmfYuvDecodes) {
  TempDir dir("ubo");
  Bytes b;
  common_header(b, "!DFMF08FCR", {{0, 0}}, {{0, 0}}, 1, 1);
  b.u32(0);  // rotations
  b.u32(1);
  b.i32(1);  // YUV
  for (int i = 0; i < 3 + 9; ++i) b.f32(0.f);
  const float yuv[3] = {0.5f, 0.1f, -0.2f};
  for (int c = 0; c < 3; ++c) {
    b.u8(2);  // half scalars
    b.u32(1);
    b.u32(1);
    b.u32(1);
    b.half(1.f);
    b.half(yuv[c]);
    b.half(1.f);
  }
  b.save(dir / "c.btf");
  EXPECT_EQ(ubo_btf_format(dir / "c.btf"), "DFMF");
  const Rgb v = read_ubo_btf(dir / "c.btf", zenith_only()).btf.value(0, 0, 0);
  const double y = half_to_float(float_to_half(0.5f)), u = half_to_float(float_to_half(0.1f)),
               w = half_to_float(float_to_half(-0.2f));
  EXPECT_NEAR(v.r, y + 1.13983 * w, 1e-6);
  EXPECT_NEAR(v.g, y - 0.39465 * u - 0.5806 * w, 1e-6);
  EXPECT_NEAR(v.b, y + 2.03211 * u, 1e-6);
}

TEST(UboBtf, HandBuiltSparseBdiDecodes) {
  TempDir dir("ubo");
  Bytes b;
  common_header(b, "!BDIF06R2!", {{0, 0}}, {{0, 0}, {50, 0}}, 2, 2);
  b.u32(1);  // one scan line (2 texels) per chunk
  b.u8(2);
  for (int m : {1, 0, 1, 1}) b.u8(m);  // texel 1 is not stored
  b.u32(0);
  // 3 stored texels: chunks of 2 and 1; per texel l = 0 then l = 1, c fastest.
  auto texel = [&](int t) {
    for (int l = 0; l < 2; ++l)
      for (int c = 0; c < 3; ++c) b.half(static_cast<float>(t * 16 + l * 4 + c));
  };
  b.u32(2 * 6 * 2);
  texel(0);
  texel(2);
  b.u32(1 * 6 * 2);
  texel(3);
  b.save(dir / "d.bdi");
  const MeasuredBtf m = read_ubo_btf(dir / "d.bdi", zenith_only());
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(m.btf.value(0, 0, 0)[c], static_cast<float>(c));
    EXPECT_EQ(m.btf.value(1, 0, 0)[c], 0.f);
    EXPECT_EQ(m.btf.value(2, 0, 0)[c], static_cast<float>(32 + c));
    EXPECT_EQ(m.btf.value(3, 0, 0)[c], static_cast<float>(48 + c));
  }
  // A chunk size that disagrees with the sampling.
  Bytes bad = b;
  bad.s[bad.s.size() - 12 - 4] = 11;
  bad.save(dir / "e.bdi");
  expect_input_error([&] { read_ubo_btf(dir / "e.bdi", zenith_only()); }, dir / "e.bdi", "chunk");
}

// --- UBO errors -----------------------------------------------------------------------------

TEST(UboBtf, EveryTruncationIsAnInputError) {
  TempDir dir("ubo");
  const Bytes full = hand_fmf();
  const fs::path file = dir / "t.btf";
  for (std::size_t n = 0; n < full.s.size(); ++n) {
    std::ofstream(file, std::ios::binary | std::ios::trunc) << full.s.substr(0, n);
    expect_input_error([&] { read_ubo_btf(file, zenith_only()); }, file);
  }
  // BDI and FMF12 writers' files too, at a few lengths.
  const Btf b = random_btf(2, 1, 2, 40);
  write_ubo_bdi(b, dir / "w.bdi");
  write_ubo_fmf(b, dir / "w.fmf");
  for (const char* name : {"w.bdi", "w.fmf"}) {
    const std::string bytes = prt::testing::slurp_file(dir / name);
    for (std::size_t n = 0; n < bytes.size(); n += 7) {
      std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes.substr(0, n);
      expect_input_error([&] { read_ubo_btf(file, zenith_only()); }, file);
    }
  }
}

TEST(UboBtf, BadHeadersAreInputErrors) {
  TempDir dir("ubo");
  const fs::path file = dir / "x.btf";
  Bytes sig;
  sig.text("!XYZ12FCER and more bytes");
  sig.save(file);
  expect_input_error([&] { read_ubo_btf(file); }, file, "signature");
  expect_input_error([&] { ubo_btf_format(file); }, file, "signature");

  // A view count that would need terabytes.
  Bytes huge;
  huge.text("!FMF06FC");
  huge.u32(264);
  huge.u32(1);
  huge.text(std::string(240 + 16, '\0'));
  huge.u32(0xFFFFFFFFu);
  huge.text(std::string(64, '\0'));
  huge.save(file);
  expect_input_error([&] { read_ubo_btf(file); }, file, "truncated");

  // Meta data block size that disagrees with its fields.
  Bytes meta = hand_fmf();
  meta.s[8] = 100;
  meta.save(file);
  expect_input_error([&] { read_ubo_btf(file); }, file, "meta data");

  // Matrices that do not fit the sampling: 11 rows instead of 12.
  Bytes rows = hand_fmf();
  const std::size_t rows_at = rows.s.size() - (1 + 12 + 4) * 4 - 8;
  rows.s[rows_at] = 11;
  rows.save(file);
  expect_input_error([&] { read_ubo_btf(file, zenith_only()); }, file, "matrices");

  // A non-square texture.
  Bytes wide;
  common_header(wide, "!FMF06FC", {{0, 0}}, {{0, 0}}, 2, 1);
  wide.save(file);
  expect_input_error([&] { read_ubo_btf(file); }, file, "square");

  // An unsupported DFMF colour model.
  Bytes lab;
  common_header(lab, "!DFMF08FCR", {{0, 0}}, {{0, 0}}, 1, 1);
  lab.u32(0);
  lab.u32(1);
  lab.i32(2);
  lab.save(file);
  expect_input_error([&] { read_ubo_btf(file); }, file, "colour model");

  expect_input_error([&] { read_ubo_btf(dir / "missing.btf"); }, dir / "missing.btf");
}

TEST(UboBtf, OversizedImportsAreInputErrorsBeforeAllocating) {
  TempDir dir("ubo");
  const fs::path file = dir / "x.btf";
  // A header declaring 65536 x 65536 texels: above Btf's 4096 without --resolution.
  Bytes huge;
  common_header(huge, "!FMF06FC", {{0, 0}}, {{0, 0}}, 65536, 65536);
  huge.save(file);
  expect_input_error([&] { read_ubo_btf(file); }, file, "65536 x 65536");
  expect_input_error([&] { read_ubo_btf(file); }, file, "--resolution");
  MeasuredImportOptions o;
  o.resolution = 4096;  // 4096^2 texels x 144 views x 64 lights: terabytes
  expect_input_error([&] { read_ubo_btf(file, o); }, file, "--view-side");

  // A complete 256 x 256 FMF (half scalars, rank 1) whose import onto 64 x 64 views and lights
  // would be 13 TB.
  Bytes fmf;
  common_header(fmf, "!FMF06FC", {{0, 0}}, {{0, 0}}, 256, 256);
  fmf.u32(1);
  fmf.u8(2);
  fmf.u32(1);
  fmf.u32(3);
  fmf.u32(256 * 256);
  fmf.half(1.f);
  for (int c = 0; c < 3; ++c) fmf.half(static_cast<float>(c + 1));
  for (int t = 0; t < 256 * 256; ++t) fmf.half(0.5f);
  fmf.save(file);
  MeasuredImportOptions wide;
  wide.view_side = 64;
  wide.light_side = 64;
  expect_input_error([&] { read_ubo_btf(file, wide); }, file, "256 x 256 measured texels");
  try {
    read_ubo_btf(file, wide);
  } catch (const InputError& e) {
    const std::string what = e.what();
    for (const char* want : {"GiB", "--resolution", "--view-side", "--light-side"})
      EXPECT_NE(what.find(want), std::string::npos) << what;
  }
  EXPECT_GT(measured_import_bytes(256, wide), measured_import_byte_limit());
  const MeasuredBtf m = read_ubo_btf(file, zenith_only());
  EXPECT_EQ(m.btf.value(12345, 0, 0).g, 1.f);
}

// The peak memory of a child process that reads UBO headers declaring 65536 x 65536 and
// 16384 x 16384 texels (at the import's default resolution and box-filtered to 1 texel): each is
// refused with an InputError before anything per texel is allocated (a 4 KB file cannot hold
// such a BTF; allocating first would take gigabytes).
TEST(UboBtf, AHugeDeclaredTexelCountIsRefusedWithoutAllocatingIt) {
  TempDir dir("ubo");
  std::vector<fs::path> files;
  for (const std::uint32_t side : {65536u, 16384u}) {
    for (const char* signature : {"!FMF06FC", "!BDIF06R2!"}) {
      Bytes b;
      common_header(b, signature, {{0, 0}}, {{0, 0}}, side, side);
      files.push_back(dir /
                      ("x" + std::to_string(side) + "-" + std::to_string(files.size()) + ".btf"));
      b.save(files.back());
    }
  }
  for (const auto& file : files)
    for (const int resolution : {0, 1}) {
      MeasuredImportOptions o;
      o.resolution = resolution;
      EXPECT_TRUE(prt::testing::refused_within_memory([&] { (void)read_ubo_btf(file, o); }, 256))
          << file << " at resolution " << resolution;
    }
}

TEST(UboBtf, BdiTexelIndexIsBoundByTheFileSize) {
  TempDir dir("ubo");
  const fs::path file = dir / "x.bdi";
  // A 1024 x 1024 mask with every texel stored, and none of the chunks.
  Bytes b;
  common_header(b, "!BDIF06R2!", {{0, 0}}, {{0, 0}}, 1024, 1024);
  b.u32(4);
  b.u8(2);
  b.text(std::string(1024 * 1024, '\1'));
  b.u32(0);
  b.save(file);
  g_largest_allocation = 0;
  expect_input_error([&] { read_ubo_btf(file, zenith_only()); }, file, "truncated");
  // The mask itself (1 MiB), not an 8 MiB texel index.
  EXPECT_LT(g_largest_allocation.load(), std::size_t{2} << 20);
}

TEST(UboBtf, NonFiniteDecodedValuesAreInputErrors) {
  TempDir dir("ubo");
  const fs::path file = dir / "x.btf";
  // FMF with a log dynamic range whose exp overflows a float: exp(100).
  Bytes b;
  common_header(b, "!FMF12FCER", {{0, 0}}, {{0, 0}}, 1, 1);
  b.u32(0);  // rotations
  b.u8(1);
  b.u32(1);  // log dynamic range
  b.u32(1);
  b.u8(4);
  b.u32(1);
  b.u32(3);
  b.u32(1);
  b.f32(1.f);
  for (float v : {1.f, 100.f, 1.f}) b.f32(v);
  b.f32(1.f);
  b.save(file);
  expect_input_error([&] { read_ubo_btf(file, zenith_only()); }, file,
                     "texel (0, 0) channel G is inf");
  // An infinite half in a BDI.
  Bytes bdi;
  common_header(bdi, "!BDIF06R2!", {{0, 0}}, {{0, 0}}, 1, 1);
  bdi.u32(1);
  bdi.u8(2);
  bdi.u8(1);
  bdi.u32(0);
  bdi.u32(3 * 2);
  bdi.half(1.f);
  bdi.half(1.f);
  bdi.u8(0x00);
  bdi.u8(0xFC);  // -inf
  bdi.save(file);
  expect_input_error([&] { read_ubo_btf(file, zenith_only()); }, file, "channel B is -inf");
}

// --- CLI ------------------------------------------------------------------------------------

TEST(MeasuredBtfCli, ExportThenImportGivesTheSameBtf) {
  TempDir dir("measured_cli");
  const Btf b = random_btf(4, 2, 2, 50);
  write_btf(b, dir / "in.prt");
  const std::string env = "PRTLAB_CACHE=\"" + (dir / "cache").string() + "\" ";
  for (const std::string format : {"utia", "ubo-fmf", "ubo-bdi"}) {
    const fs::path out = dir / ("out-" + format);
    auto r = prt::testing::run_cli(fmt::format("btf export \"{}\" --format {} --out \"{}\" --json",
                                               (dir / "in.prt").string(), format, out.string()),
                                   dir.path(), env);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out).at("format"), format);
    const fs::path prt = dir / ("back-" + format + ".prt");
    r = prt::testing::run_cli(
        fmt::format(
            "btf import \"{}\" --format {} --view-side 2 --light-side 2 --out \"{}\" --json",
            out.string(), format == "utia" ? "utia" : "ubo", prt.string()),
        dir.path(), env);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j.at("coverage").at("views_used"), 4);
    EXPECT_LT(j.at("coverage").at("max_light_angle_deg").get<double>(), 0.71);
    const Btf back = read_btf(prt);
    EXPECT_LT(max_relative_error(back, b), format == "ubo-bdi" ? 1.0 / 2048 : 3e-7) << format;
    // The imported archive is a BTF file like any other.
    r = prt::testing::run_cli(fmt::format("btf info \"{}\" --json", prt.string()), dir.path(), env);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out).at("source"), "file");
  }
  const auto r = prt::testing::run_cli(
      fmt::format("btf import \"{}\" --format ubo --resolution 3 --out \"{}\"",
                  (dir / "out-ubo-fmf").string(), (dir / "x.prt").string()),
      dir.path(), env);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("must divide"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace prt
