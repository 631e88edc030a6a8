// `prtlab experiment table1` run as a user would, on the tiny scene: the JSON it prints and the
// files it writes, and an unknown scene that fails with a clear message and writes nothing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
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

TEST_F(ExperimentCli, AllQuickRunsEveryExperimentAndThenSkipsTheCompleteOnes) {
  // `experiment all --quick` on the tiny scene: both tables (into tables-quick/) and every
  // experiment file's quick variant, each folder complete; a second call skips them all.
  const auto out = dir_ / "results";
  const std::string cmd =
      "--no-opencl experiment all --quick --scenes tiny-sphere-plane --no-plot --out \"" +
      out.string() + "\"";
  const auto r = run_cli(cmd, dir_, env_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* f : {"tables-quick/table1.md", "tables-quick/table2.md"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  for (const char* name : {"fig6-quick", "fig8-quick", "pareto-quick", "skip-quick"}) {
    EXPECT_TRUE(fs::exists(out / name / ".complete")) << name;
    EXPECT_TRUE(fs::exists(out / name / "README.md")) << name;
    EXPECT_TRUE(fs::exists(out / name / "points.csv")) << name;
  }
  // The material table, its images on the --scenes scene.
  EXPECT_TRUE(fs::exists(out / "btf-table-quick" / ".complete"));
  EXPECT_TRUE(fs::exists(out / "btf-table-quick" / "table.csv"));
  EXPECT_TRUE(
      fs::exists(out / "btf-table-quick" / "images" / "tiny-sphere-plane-checker-full.png"));
  const auto again = run_cli(cmd, dir_, env_);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NE(again.err.find("fig6-quick is complete"), std::string::npos) << again.err;
  EXPECT_NE(again.err.find("btf-table-quick is complete"), std::string::npos) << again.err;
  // The stability suite, its own kind too.
  EXPECT_TRUE(fs::exists(out / "stability-quick" / ".complete"));
  EXPECT_TRUE(fs::exists(out / "stability-quick" / "cases.csv"));
  EXPECT_NE(again.err.find("stability-quick is complete"), std::string::npos) << again.err;

  const auto list = run_cli("experiment list --json", dir_, env_);
  ASSERT_EQ(list.exit_code, 0) << list.err;
  const auto j = nlohmann::json::parse(list.out);
  std::vector<std::string> names;
  for (const auto& e : j.at("experiments")) names.push_back(e.at("name"));
  for (const char* n : {"fig6", "fig8", "pareto", "skip"})
    EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
}

TEST_F(ExperimentCli, RunRefusesAMissingFileAndAnUnknownExperiment) {
  const auto missing = run_cli("experiment run no/such/file.toml", dir_, env_);
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("no such experiment file"), std::string::npos) << missing.err;
  const auto unknown = run_cli("experiment run fig66", dir_, env_);
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_NE(unknown.err.find("known: "), std::string::npos) << unknown.err;
  const auto report =
      run_cli("experiment report \"" + (dir_ / "nothing").string() + "\"", dir_, env_);
  EXPECT_EQ(report.exit_code, 1);
  EXPECT_NE(report.err.find("result.json"), std::string::npos) << report.err;
}

}  // namespace
}  // namespace prt
