// `prtlab render` and `prtlab fps` on the tiny test scene, run as a user would: the images are
// readable, the JSON keys are there, the frame loops relight only on light changes, and a bad
// environment, view, backend or output name is an error that names it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <set>

#include "prtlab/image/image_io.h"
#include "support/cli_runner.h"

namespace prt {
namespace {
namespace fs = std::filesystem;
using prt::testing::run_cli;

class RenderCli : public ::testing::Test {
 protected:
  // One directory and stage cache for the suite: T, the compressed transfer and the BTFs are
  // computed by the first test and loaded by the others.
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("prtlab_render_cli_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // A small lat-long sky: bright above, dim below, warmer towards +x.
    RgbImage sky(32, 16);
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 32; ++x)
        sky.at(x, y) = y < 8 ? Rgb(1.0f + 0.1f * x, 1.0f, 1.5f) : Rgb(0.1f, 0.1f, 0.1f);
    write_exr(sky, dir_ / "sky.exr");
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  prt::testing::CliResult run(const std::string& args) const {
    return run_cli(args, dir_, "PRTLAB_CACHE=\"" + (dir_ / "cache").string() + "\" ");
  }
  static std::string sky() { return (dir_ / "sky.exr").string(); }
  static std::string small() {
    return " --btf-resolution 8 --width 64 --height 48 --backend uncompressed ";
  }

  static fs::path dir_;
};
fs::path RenderCli::dir_;

TEST_F(RenderCli, WritesReadableExrAndPng) {
  const auto out = dir_ / "img" / "tiny.exr";
  const auto r = run("-q render tiny-sphere-plane --env " + sky() + small() + "--out " +
                     out.string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["width"], 64);
  EXPECT_EQ(j["height"], 48);
  EXPECT_GT(j["hit_pixels"].get<int>(), 100);
  for (const char* key : {"gbuffer_ms", "project_ms", "relight_ms", "upload_ms", "shade_ms"})
    EXPECT_TRUE(j["stages"].contains(key)) << key;
  EXPECT_TRUE(j.contains("prtlab"));
  EXPECT_EQ(j["material"], "full");  // the default material
  EXPECT_TRUE(j["material_parameters"].contains("seed"));

  const RgbImage image = read_exr(out);
  ASSERT_EQ(image.width, 64);
  ASSERT_EQ(image.height, 48);
  double sum = 0;
  for (const auto& p : image.pixels)
    for (int c = 0; c < 3; ++c) {
      EXPECT_TRUE(std::isfinite(p[c]));
      EXPECT_GE(p[c], 0.0f);
      sum += p[c];
    }
  EXPECT_GT(sum, 0.0);
  const std::string png = prt::testing::slurp_file(dir_ / "img" / "tiny.png");
  ASSERT_GE(png.size(), 8u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  // No temporary files left beside the outputs.
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir_ / "img")) {
    (void)e;
    ++files;
  }
  EXPECT_EQ(files, 2);
}

TEST_F(RenderCli, PngOnlyAndViewPreset) {
  const auto out = dir_ / "top.png";
  const auto r = run("-q render tiny-sphere-plane --env " + sky() + small() +
                     "--view top --rotate 90 --filter bilinear --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(out));
  EXPECT_FALSE(fs::exists(dir_ / "top.exr"));
  EXPECT_NE(r.out.find("view top"), std::string::npos) << r.out;
}

TEST_F(RenderCli, RejectsUnknownInputsNamingThem) {
  const auto out = " --out " + (dir_ / "bad.exr").string();
  auto r = run("-q render tiny-sphere-plane --env nosuchenv" + small() + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("nosuchenv"), std::string::npos) << r.err;

  r = run("-q render tiny-sphere-plane --env " + sky() + small() + "--view nosuchview" + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("nosuchview"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("front"), std::string::npos) << "lists the presets: " << r.err;

  r = run("-q render tiny-sphere-plane --env " + sky() +
          " --btf-resolution 8 --backend nosuchbackend" + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("nosuchbackend"), std::string::npos) << r.err;

  r = run("-q render tiny-sphere-plane --env " + sky() + small() + "--material nosuchmaterial" +
          out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("nosuchmaterial"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("full"), std::string::npos) << "lists the materials: " << r.err;

  r = run("-q render tiny-sphere-plane --env " + sky() + small() +
          "--material full --material-param nosuchkey=1" + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("nosuchkey"), std::string::npos) << r.err;

  r = run("-q fps tiny-sphere-plane --env " + sky() + small() + "--frames 1 --primary-rays rays");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("'rays'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("packets"), std::string::npos) << "lists the choices: " << r.err;

  r = run("-q render nosuchscene --env " + sky() + small() + out);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("nosuchscene"), std::string::npos) << r.err;

  r = run("-q render tiny-sphere-plane --env " + sky() + small() + " --out " +
          (dir_ / "bad.jpg").string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("bad.jpg"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "bad.exr"));
}

TEST_F(RenderCli, FpsRelightsOnlyOnLightChangesAndWritesReports) {
  const auto md = dir_ / "fps" / "tiny.md";
  // Without culling a view change relights nothing at all; with it, a view change relights the
  // vertices it reveals (FrameCulling tests), so the strict property is checked culling off.
  const auto r = run("-q fps tiny-sphere-plane --no-cull --env " + sky() + small() +
                     "--frames 3 --json --out " + md.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["view_change"]["relights"], 0);
  EXPECT_EQ(j["view_change"]["gbuffer_traces"], 3);
  EXPECT_EQ(j["light_change"]["relights"], 3);
  EXPECT_EQ(j["light_change"]["gbuffer_traces"], 0);
  // Frame times: each loop's median, its fps, and their ratio; a view-change frame runs no
  // light stage and a light-change frame no G-buffer stage.
  const double view_ms = j["view_change"]["median_frame_ms"].get<double>();
  const double light_ms = j["light_change"]["median_frame_ms"].get<double>();
  ASSERT_GT(view_ms, 0.0);
  ASSERT_GT(light_ms, 0.0);
  EXPECT_DOUBLE_EQ(j["view_change"]["fps"].get<double>(), 1000.0 / view_ms);
  EXPECT_DOUBLE_EQ(j["light_change"]["fps"].get<double>(), 1000.0 / light_ms);
  EXPECT_DOUBLE_EQ(j["view_to_light_frame_ratio"].get<double>(), view_ms / light_ms);
  const auto& view_stages = j["view_change"]["stages_median"];
  const auto& light_stages = j["light_change"]["stages_median"];
  EXPECT_EQ(view_stages["project_ms"].get<double>(), 0.0);
  EXPECT_EQ(view_stages["relight_ms"].get<double>(), 0.0);
  EXPECT_GT(view_stages["gbuffer_ms"].get<double>(), 0.0);
  EXPECT_EQ(light_stages["gbuffer_ms"].get<double>(), 0.0);
  EXPECT_GT(light_stages["relight_ms"].get<double>(), 0.0);
  EXPECT_TRUE(j["paper"].is_null()) << "the paper has no tiny scene";
  EXPECT_TRUE(j["provenance"].contains("git"));
  EXPECT_TRUE(fs::exists(md));
  const auto written = nlohmann::json::parse(prt::testing::slurp_file(dir_ / "fps" / "tiny.json"));
  EXPECT_EQ(written["light_change"]["relights"], 3);
  EXPECT_NE(prt::testing::slurp_file(md).find("| **fps** |"), std::string::npos);

  // The cost model: the upload's bytes from the hit and pixel counts, and every stage's model
  // time recomputed from its bytes and FLOPs at the GTX 280's nominal figures.
  const double pixels = j["width"].get<double>() * j["height"].get<double>();
  const double hits = j["hit_pixels"].get<double>();
  std::set<std::string> stages;
  for (const auto& c : j["cost_model"]) {
    stages.insert(c["change"].get<std::string>() + "/" + c["stage"].get<std::string>());
    const double bytes = c["bytes"].get<double>(), flops = c["flops"].get<double>();
    EXPECT_GT(bytes, 0.0) << c["stage"];
    const double gtx = c["model_ms"]["GTX 280 (the paper's, 2008)"].get<double>();
    const double expected = c["upload"].get<bool>()
                                ? bytes / 6.0e9 * 1e3
                                : std::max(bytes / 141.7e9, flops / 933.0e9) * 1e3;
    EXPECT_NEAR(gtx, expected, 1e-9 * expected) << c["stage"];
    if (c["stage"] == "G-buffer upload") {
      EXPECT_EQ(bytes, 44.0 * hits + 4.0 * pixels);
    }
  }
  for (const char* s : {"view/G-buffer", "view/G-buffer upload", "view/view cache + shade hits",
                        "light/relight", "light/cached shade"})
    EXPECT_TRUE(stages.contains(s)) << s;
  EXPECT_NE(prt::testing::slurp_file(md).find("## Cost model"), std::string::npos);
}

}  // namespace
}  // namespace prt
