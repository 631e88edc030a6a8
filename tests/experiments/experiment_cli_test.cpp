// `prtlab experiment table1` run as a user would, on the tiny scene: the JSON it prints and the
// files it writes, and an unknown scene that fails with a clear message and writes nothing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "support/cli_runner.h"
#include "support/temp_dir.h"

namespace prt {
namespace {
namespace fs = std::filesystem;
using prt::testing::run_cli;

class ExperimentCli : public ::testing::Test {
 protected:
  void SetUp() override { env_ = "PRTLAB_CACHE=\"" + (dir_ / "cache").string() + "\" "; }
  prt::testing::TempDir tmp_{"experiment_cli"};
  fs::path dir_ = tmp_.path();
  std::string env_;
};

TEST_F(ExperimentCli, Table1OnTheTinySceneWritesItsFiles) {
  const auto out = dir_ / "results";
  const auto r = run_cli("-q --no-opencl experiment table1 --scenes tiny-sphere-plane --out \"" +
                             out.string() + "\" --repeats 1 --lights 1 --no-plot --json",
                         dir_, env_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("experiment"), "table1");
  ASSERT_EQ(j.at("rows").size(), 1u);
  const auto& row = j.at("rows")[0];
  EXPECT_EQ(row.at("scene"), "tiny-sphere-plane");
  EXPECT_TRUE(row.at("lossless").at("exact").get<bool>());
  EXPECT_TRUE(row.at("relight_ms").at("backend_opencl").is_null());  // --no-opencl
  EXPECT_NEAR(row.at("computation_percent").get<double>(),
              100 * row.at("reduced_mflops").get<double>() / row.at("mflops").get<double>(), 1e-9);
  EXPECT_NE(j.at("provenance").at("command").get<std::string>().find("--scenes tiny-sphere-plane"),
            std::string::npos);
  EXPECT_TRUE(j.contains("prtlab"));
  for (const char* f : {"table1.md", "table1.csv", "table1.json"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  EXPECT_FALSE(fs::exists(out / "table1.png"));  // --no-plot
}

TEST_F(ExperimentCli, UnknownSceneIsAClearErrorAndWritesNothing) {
  const auto out = dir_ / "results";
  const auto r = run_cli("experiment table2 --scenes no-such-scene --out \"" + out.string() + "\"",
                         dir_, env_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("scene 'no-such-scene' not found"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  const auto t3 = run_cli("experiment table3", dir_, env_);
  EXPECT_NE(t3.exit_code, 0);
}

}  // namespace
}  // namespace prt
