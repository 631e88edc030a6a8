// `prtlab image diff` and `prtlab image reference` run as a user would: exit codes, output
// files, the documented JSON keys, metrics against hand-computed values, and errors that name
// the file.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "prtlab/lighting/environment_map.h"
#include "prtlab/image/image_io.h"
#include "support/cli_runner.h"

namespace prt {
namespace {

namespace fs = std::filesystem;

class ImageCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("prtlab_image_cli_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    env_ = "PRTLAB_CACHE=\"" + (dir_ / "cache").string() + "\" ";
    // Reference (1, 2, 2), (0, 0, 4); image (1, 2, 3), (0, 1, 4): relative L2 sqrt(2) / 5,
    // RMSE sqrt(1/3), peak 4, PSNR 20 log10(4 sqrt 3), max 1.
    RgbImage ref(2, 1), img(2, 1);
    ref.pixels = {{1, 2, 2}, {0, 0, 4}};
    img.pixels = {{1, 2, 3}, {0, 1, 4}};
    write_exr(ref, ref_ = dir_ / "ref.exr");
    write_exr(img, img_ = dir_ / "img.exr");
  }
  void TearDown() override { fs::remove_all(dir_); }

  prt::testing::CliResult run(const std::string& args) const {
    return prt::testing::run_cli(args, dir_, env_);
  }
  static std::string q(const fs::path& p) {
    std::string quoted = "\"";
    quoted += p.string();
    quoted += '"';
    return quoted;
  }

  fs::path dir_, ref_, img_;
  std::string env_;
};

TEST_F(ImageCli, DiffPrintsHandComputedMetrics) {
  const fs::path png = dir_ / "out" / "err.png", report = dir_ / "report.json";
  const auto r = run("image diff " + q(img_) + " " + q(ref_) + " --out " + q(png) + " --report " +
                     q(report) + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key :
       {"image", "reference", "mask", "width", "height", "error", "false_colour", "prtlab"})
    EXPECT_TRUE(j.contains(key)) << key;
  const auto& e = j["error"];
  EXPECT_NEAR(e["relative_l2"].get<double>(), std::sqrt(2.0) / 5.0, 1e-9);
  EXPECT_NEAR(e["rmse"].get<double>(), std::sqrt(1.0 / 3.0), 1e-9);
  EXPECT_NEAR(e["psnr_db"].get<double>(), 20.0 * std::log10(4.0 * std::sqrt(3.0)), 1e-9);
  EXPECT_EQ(e["max_abs"].get<double>(), 1.0);
  EXPECT_EQ(e["peak"].get<double>(), 4.0);
  EXPECT_EQ(e["pixels"], 2);
  EXPECT_TRUE(j["mask"].is_null());
  EXPECT_EQ(j["false_colour"]["colour_map"], "viridis");
  EXPECT_GT(j["false_colour"]["scale"].get<double>(), 0.0);
  EXPECT_TRUE(fs::exists(png));
  // The report carries the same metrics and the provenance of experiments/provenance.h.
  const auto rep = nlohmann::json::parse(prt::testing::slurp_file(report));
  EXPECT_EQ(rep["error"], j["error"]);
  for (const char* key : {"version", "git", "compiler", "machine", "date_utc", "command"})
    EXPECT_TRUE(rep["provenance"].contains(key)) << key;
  // No temporary files left behind.
  for (const auto& entry : fs::recursive_directory_iterator(dir_))
    EXPECT_EQ(entry.path().string().find(".tmp."), std::string::npos) << entry.path();

  // Human-readable output, and a fixed scale.
  const auto text =
      run("image diff " + q(img_) + " " + q(ref_) + " --out " + q(png) + " --scale 0.5");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("relative L2"), std::string::npos);
  EXPECT_NE(text.out.find("PSNR"), std::string::npos);
  EXPECT_NE(text.out.find("0 .. 0.5"), std::string::npos) << text.out;
}

TEST_F(ImageCli, DiffWithMask) {
  RgbImage mask(2, 1);
  mask.pixels = {{1, 1, 1}, {0, 0, 0}};
  const fs::path m = dir_ / "mask.exr";
  write_exr(mask, m);
  const auto r = run("image diff " + q(img_) + " " + q(ref_) + " --mask " + q(m) + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["error"]["pixels"], 1);
  EXPECT_NEAR(j["error"]["relative_l2"].get<double>(), 1.0 / 3.0, 1e-9);
}

TEST_F(ImageCli, DiffErrorsNameTheFile) {
  const fs::path missing = dir_ / "missing.exr";
  auto r = run("image diff " + q(missing) + " " + q(ref_));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("missing.exr"), std::string::npos) << r.err;

  const fs::path junk = dir_ / "junk.exr";
  { std::ofstream(junk) << "not an exr"; }
  r = run("image diff " + q(img_) + " " + q(junk));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("junk.exr"), std::string::npos) << r.err;

  const fs::path big = dir_ / "big.exr";
  write_exr(RgbImage(3, 2), big);
  r = run("image diff " + q(big) + " " + q(ref_));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("big.exr is 3 x 2"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("ref.exr is 2 x 1"), std::string::npos) << r.err;

  r = run("image diff " + q(img_) + " " + q(ref_) + " --out " + q(dir_ / "err.jpg"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(".png"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "err.jpg"));
}

TEST_F(ImageCli, ReferenceOfTheTinyScene) {
  // A smooth procedural sky as the user's lat-long EXR; tiny BTFs so that generating them
  // takes no time.
  SunSky sky;
  sky.sun = Rgb(4.f);
  sky.sun_radius_rad = 0.3;
  const LatLongImage ll = sky.to_latlong(64, 32);
  RgbImage env(ll.width, ll.height);
  env.pixels = ll.texels;
  const fs::path env_file = dir_ / "sky.exr";
  write_exr(env, env_file);

  const fs::path out = dir_ / "ref.exr", hits = dir_ / "hits.exr", pw = dir_ / "pw.exr",
                 se = dir_ / "se.exr";
  const std::string common = " tiny-sphere-plane --env " + q(env_file) +
                             " --size 32x24 --btf-resolution 4 --samples 4 --env-lookup cubemap";
  const auto r = run("-q image reference" + common + " --out " + q(out) + " --hits " + q(hits) +
                     " --pointwise " + q(pw) + " --stderr " + q(se) + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key :
       {"scene", "env", "env_lookup", "view", "width", "height", "hit_pixels", "samples_per_pixel",
        "seed", "rays_traced", "render_seconds", "relative_noise", "exr", "png", "stderr_exr",
        "hits_exr", "pointwise_exr", "prtlab"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["samples_per_pixel"], 16);
  EXPECT_EQ(j["width"], 32);
  EXPECT_GT(j["hit_pixels"].get<int>(), 100);
  EXPECT_GT(j["rays_traced"].get<std::uint64_t>(), 0u);
  const RgbImage radiance = read_exr(out);
  EXPECT_EQ(radiance.width, 32);
  EXPECT_EQ(radiance.height, 24);
  EXPECT_TRUE(fs::exists(dir_ / "ref.png"));
  EXPECT_EQ(read_exr(se).width, 32);

  // The same seed gives the same image; the pointwise-transfer render is close to it.
  const fs::path again = dir_ / "again.exr";
  ASSERT_EQ(run("-q image reference" + common + " --out " + q(again)).exit_code, 0);
  EXPECT_EQ(read_exr(again).pixels, radiance.pixels);
  const auto d = run("image diff " + q(pw) + " " + q(out) + " --mask " + q(hits) + " --json");
  ASSERT_EQ(d.exit_code, 0) << d.err;
  const auto dj = nlohmann::json::parse(d.out);
  EXPECT_EQ(dj["error"]["pixels"], j["hit_pixels"]);
  EXPECT_LT(dj["error"]["relative_l2"].get<double>(), 0.6);

  // Bad options are errors before any work.
  auto bad = run("image reference tiny-sphere-plane --env " + q(env_file) + " --samples 3 --out " +
                 q(dir_ / "x.exr"));
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("--samples"), std::string::npos) << bad.err;
  bad =
      run("image reference tiny-sphere-plane --env " + q(env_file) + " --out " + q(dir_ / "x.png"));
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find(".exr"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace prt
