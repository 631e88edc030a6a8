// `prtlab env info`, `prtlab env cubemap` and `prtlab env fit-srbf` run as a user would: exit
// codes, output files, the documented JSON keys, and errors that name the file.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "prtlab/image/image_io.h"
#include "prtlab/lighting/environment_map.h"
#include "support/cli_runner.h"

namespace prt {
namespace {

namespace fs = std::filesystem;

using RunResult = prt::testing::CliResult;
using prt::testing::slurp_file;

class EnvCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("prtlab_env_cli_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // A small procedural environment, written as a user's lat-long EXR would be.
    SunSky env;
    const LatLongImage ll = env.to_latlong(128, 64);
    RgbImage img(ll.width, ll.height);
    img.pixels = ll.texels;
    exr_ = dir_ / "sky.exr";
    write_exr(img, exr_);
    power_ = ll.total_power();
  }
  void TearDown() override { fs::remove_all(dir_); }

  RunResult run(const std::string& args) const { return prt::testing::run_cli(args, dir_); }

  fs::path dir_, exr_;
  Vec3d power_{0.0};
};

TEST_F(EnvCli, CubemapWritesStripAndPreview) {
  const fs::path out = dir_ / "cube.exr", png = dir_ / "cube.png";
  const RunResult r = run("env cubemap \"" + exr_.string() + "\" --res 8 --out \"" + out.string() +
                          "\" --preview \"" + png.string() + "\" --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(fs::exists(out));
  ASSERT_TRUE(fs::exists(png));
  EXPECT_GT(fs::file_size(png), 0u);
  const RgbImage strip = read_exr(out);
  EXPECT_EQ(strip.width, 48);
  EXPECT_EQ(strip.height, 8);

  const nlohmann::json j = nlohmann::json::parse(r.out);
  for (const char* key :
       {"file", "width", "height", "resolution", "out", "preview", "power_latlong", "power_cubemap",
        "power_relative_difference", "invalid_texels", "resample_seconds", "prtlab"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["resolution"], 8);
  EXPECT_EQ(j["width"], 128);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(j["power_latlong"][c].get<double>(), power_[c], 1e-9 * power_[c]);
    EXPECT_NEAR(j["power_cubemap"][c].get<double>(), power_[c], 1e-6 * power_[c]);
    EXPECT_LT(std::abs(j["power_relative_difference"][c].get<double>()), 1e-6);
  }
  // The strip on disk carries the same power.
  const Cubemap back = cubemap_from_strip_image(strip, out);
  EXPECT_NEAR(back.total_power().x, power_.x, 1e-6 * power_.x);

  // Without --json: human-readable, still exit 0; without --preview no PNG is needed.
  const RunResult text = run("env cubemap \"" + exr_.string() + "\" --res 4 --out \"" +
                             (dir_ / "c4.exr").string() + "\"");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("power cubemap"), std::string::npos) << text.out;
  EXPECT_TRUE(fs::exists(dir_ / "c4.exr"));
}

TEST_F(EnvCli, InfoJsonHasTheDocumentedKeys) {
  const RunResult r = run("env info \"" + exr_.string() + "\" --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  for (const char* key :
       {"file", "width", "height", "min", "max", "mean", "power", "invalid_texels"}) {
    ASSERT_TRUE(j.contains(key)) << key << " missing in " << r.out;
  }
  for (const char* key : {"min", "max", "mean", "power"}) {
    ASSERT_TRUE(j[key].is_array() && j[key].size() == 3) << key;
  }
  EXPECT_EQ(j["file"], exr_.string());
  EXPECT_EQ(j["width"], 128);
  EXPECT_EQ(j["height"], 64);
  EXPECT_EQ(j["invalid_texels"], 0);
  const SunSky env;
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(j["power"][c].get<double>(), power_[c], 1e-9 * power_[c]);
    EXPECT_NEAR(j["mean"][c].get<double>(), power_[c] / kFourPi, 1e-9 * power_[c]);
    EXPECT_NEAR(j["max"][c].get<double>(), env.sun[c], 1e-3);  // sun texels are fully lit
    EXPECT_NEAR(j["min"][c].get<double>(), env.ground[c], 1e-6);
  }
  const RunResult text = run("env info \"" + exr_.string() + "\"");
  ASSERT_EQ(text.exit_code, 0);
  EXPECT_NE(text.out.find("128 x 64"), std::string::npos) << text.out;
}

TEST_F(EnvCli, FitSrbfWritesTheFitAndBeatsUniformSrbfs) {
  const fs::path out = dir_ / "fit.json", png = dir_ / "fit.png";
  const RunResult r =
      run("-q env fit-srbf \"" + exr_.string() + "\" --count 8 --res 8 --rounds 10 --out \"" +
          out.string() + "\" --preview \"" + png.string() + "\" --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key :
       {"file", "resolution", "seeding", "rounds", "lbfgs_line_search_failures", "seconds",
        "initial_relative_error", "relative_error", "uniform_count", "uniform_bandwidth",
        "uniform_relative_error", "out", "preview", "provenance"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["uniform_count"], 16);
  // The sun and sky: a small bright source the scattered SRBFs can sit on.
  EXPECT_LT(j["relative_error"].get<double>(), j["uniform_relative_error"].get<double>());
  EXPECT_LE(j["relative_error"].get<double>(), j["initial_relative_error"].get<double>());
  ASSERT_TRUE(fs::exists(png));
  const auto fit = nlohmann::json::parse(slurp_file(out));
  ASSERT_EQ(fit["fit"]["srbfs"].size(), 8u);
  EXPECT_EQ(fit["fit"]["parameters"], 48);
  EXPECT_TRUE(fit["fit"]["srbfs"][0].contains("bandwidth"));
  // A seeding that does not exist is an error naming the option.
  const RunResult bad = run("env fit-srbf \"" + exr_.string() + "\" --seeding random");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("seeding"), std::string::npos) << bad.err;
}

TEST_F(EnvCli, MissingFileExitsOneNamingIt) {
  const fs::path missing = dir_ / "no_such_env.exr";
  for (const std::string& args : {"env info \"" + missing.string() + "\"",
                                  "env cubemap \"" + missing.string() + "\" --res 4 --out \"" +
                                      (dir_ / "x.exr").string() + "\""}) {
    const RunResult r = run(args);
    EXPECT_EQ(r.exit_code, 1) << args;
    EXPECT_NE(r.err.find("no_such_env.exr"), std::string::npos) << r.err;
  }
  // Not an EXR at all.
  std::ofstream(dir_ / "text.exr") << "hello";
  const RunResult r = run("env info \"" + (dir_ / "text.exr").string() + "\"");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("text.exr"), std::string::npos) << r.err;
}

TEST_F(EnvCli, HelpAndBadOptions) {
  for (const char* cmd : {"env --help", "env info --help", "env cubemap --help"}) {
    const RunResult r = run(cmd);
    EXPECT_EQ(r.exit_code, 0) << cmd;
    EXPECT_NE(r.out.find("Usage"), std::string::npos) << cmd << ": " << r.out;
  }
  EXPECT_NE(run("env cubemap --help").out.find("--preview"), std::string::npos);
  // --res out of range and a missing --out are usage errors (non-zero, nothing written).
  EXPECT_NE(run("env cubemap \"" + exr_.string() + "\" --res 0 --out \"" +
                (dir_ / "y.exr").string() + "\"")
                .exit_code,
            0);
  EXPECT_NE(run("env cubemap \"" + exr_.string() + "\" --res 4").exit_code, 0);
  EXPECT_FALSE(fs::exists(dir_ / "y.exr"));
}

TEST_F(EnvCli, AFailingPreviewLeavesNoCubemapBehind) {
  const fs::path out = dir_ / "cube.exr";
  // A path below a regular file cannot be created.
  const RunResult r = run("env cubemap \"" + exr_.string() + "\" --res 4 --out \"" + out.string() +
                          "\" --preview \"" + (exr_ / "p.png").string() + "\"");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_FALSE(fs::exists(out)) << "the cubemap was written though its preview failed";
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().string().find(".tmp."), std::string::npos) << e.path();
}

// Radiance near float's range would overflow every relight to +Inf: refused, naming the file.
// Large but summable radiance and a map that is not 2:1 are accepted with named warnings.
TEST_F(EnvCli, ExtremeRadianceIsRefusedAndOddMapsWarnByName) {
  auto write_map = [&](const std::string& name, int w, int h, float peak) {
    RgbImage img(w, h);
    for (Rgb& p : img.pixels) p = Rgb(0.5f);
    img.at(w / 2, h / 4) = Rgb(peak, 1.f, 1.f);
    write_exr(img, dir_ / name);
    return (dir_ / name).string();
  };
  const std::string huge = write_map("huge.exr", 64, 32, 3.0e38f);
  const RunResult refused = run("env info \"" + huge + "\"");
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.err.find(huge), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("overflow"), std::string::npos) << refused.err;

  const RunResult bright =
      run("env info \"" + write_map("bright.exr", 64, 32, 1e17f) + "\" --json");
  ASSERT_EQ(bright.exit_code, 0) << bright.err;
  EXPECT_EQ(nlohmann::json::parse(bright.out)["warnings"].value("radiance-range", 0), 1);
  EXPECT_NE(bright.err.find("[radiance-range]"), std::string::npos) << bright.err;

  const RunResult square = run("env info \"" + write_map("square.exr", 32, 32, 1.f) + "\" --json");
  ASSERT_EQ(square.exit_code, 0) << square.err;
  const nlohmann::json j = nlohmann::json::parse(square.out);
  EXPECT_EQ(j["warnings"].value("latlong-aspect", 0), 1);
  EXPECT_EQ(j["aspect_2_to_1"], false);
  const RunResult plain = run("env info \"" + exr_.string() + "\" --json");
  EXPECT_TRUE(nlohmann::json::parse(plain.out)["warnings"].empty()) << plain.out;
}

TEST_F(EnvCli, AnUnknownCommandIsNamed) {
  const RunResult top = run("fooo");
  EXPECT_NE(top.exit_code, 0);
  EXPECT_NE(top.err.find("unknown command 'fooo'"), std::string::npos) << top.err;
  EXPECT_NE(top.err.find("render"), std::string::npos) << "the commands are listed: " << top.err;
  const RunResult sub = run("env cubmap x.exr");
  EXPECT_NE(sub.exit_code, 0);
  EXPECT_NE(sub.err.find("unknown command 'cubmap' for 'prtlab env'"), std::string::npos)
      << sub.err;
  EXPECT_NE(sub.err.find("cubemap"), std::string::npos) << sub.err;
}

}  // namespace
}  // namespace prt
