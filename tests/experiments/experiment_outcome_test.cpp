// The harness never reports success for a run that measured nothing, and names every bad
// input where it is written: environment maps read before any stage, failed points as a
// non-zero exit, an all-failed run left incomplete, grids counted (and refused above
// --max-points) before they run, backends listed twice refused, and parser errors that name
// the real line.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "experiment_run.h"
#include "experiment_spec.h"
#include "prtlab/base/error.h"
#include "prtlab/compress/compressor_registry.h"
#include "run_plan.h"
#include "support/cli_runner.h"
#include "support/temp_dir.h"

namespace prt::experiments {
namespace {
namespace fs = std::filesystem;
using prt::testing::run_cli;

class ExperimentOutcome : public ::testing::Test {
 protected:
  fs::path write(const std::string& name, const std::string& body) {
    const fs::path f = dir_ / name;
    std::ofstream(f) << body;
    return f;
  }
  ExperimentSpec parse(const fs::path& f, const std::string& variant = "") {
    return parse_experiment(f, variant, CompressorRegistry::instance().names());
  }
  RunOptions options() {
    RunOptions o;
    o.out_root = dir_ / "results";
    o.cache_root = dir_ / "cache";
    o.show_progress_bars = false;
    return o;
  }
  // The message of the InputError that parsing `body` throws ("" when it parses).
  std::string parse_error(const std::string& body, const std::string& variant = "") {
    try {
      (void)parse(write("bad.toml", body), variant);
    } catch (const InputError& e) {
      return e.what();
    }
    return {};
  }
  // A scene whose file parses but whose mesh cannot be read: its preparation fails.
  fs::path broken_scene() {
    write("bad.off", "OFF\ngarbage\n");
    return write("broken.toml",
                 "name = \"broken\"\nlocal_grid = 4\ncubemap_resolution = 8\n[[part]]\n"
                 "name = \"x\"\nmesh = \"bad.off\"\nbtf = \"lambert\"\n");
  }
  prt::testing::TempDir tmp_{"experiment_outcome"};
  fs::path dir_ = tmp_.path();
};

constexpr const char* kHead =
    "name = \"x\"\nkind = \"sweep\"\nscenes = [\"tiny-sphere-plane\"]\nbackends = "
    "[\"uncompressed\"]\n";

TEST_F(ExperimentOutcome, TypeAndRangeErrorsNameTheirLine) {
  // Line 5 in the file itself, line 8 inside a variant (moved into place, not copied).
  std::string e = parse_error(std::string(kHead) + "repeats = \"five\"\n");
  EXPECT_NE(e.find("line 5: 'repeats' has the wrong type"), std::string::npos) << e;
  e = parse_error(std::string(kHead) + "[image]\nwidth = 3\n");
  EXPECT_NE(e.find("line 6: 'image.width' = 3 is outside 8..8192"), std::string::npos) << e;
  e = parse_error(std::string(kHead) + "repeats = 3\n[variant.quick]\nrepeats = 0\n", "quick");
  EXPECT_NE(e.find("line 7: 'repeats' = 0"), std::string::npos) << e;
  EXPECT_EQ(e.find("line 0"), std::string::npos) << e;
}

TEST_F(ExperimentOutcome, AnUnknownKindListsEveryKind) {
  const std::string e =
      parse_error("name = \"x\"\nscenes = [\"bunny\"]\nkind = \"equal-storage\"\n");
  EXPECT_NE(e.find("line 3: unknown kind 'equal-storage'"), std::string::npos) << e;
  for (const auto& k : experiment_kinds()) EXPECT_NE(e.find(k), std::string::npos) << k;
}

TEST_F(ExperimentOutcome, ABackendListedTwiceOrBesideTheWildcardIsRefused) {
  std::string e =
      parse_error("name = \"x\"\nscenes = [\"bunny\"]\nbackends = [\"haar\", \"haar\"]\n");
  EXPECT_NE(e.find("line 3: backend 'haar' is listed twice"), std::string::npos) << e;
  e = parse_error("name = \"x\"\nscenes = [\"bunny\"]\nbackends = [\"*\", \"haar\"]\n");
  EXPECT_NE(e.find("'*' already lists every registered backend"), std::string::npos) << e;
}

TEST_F(ExperimentOutcome, ABackendWithAGridAndPointsIsRefusedAtItsLine) {
  const std::string body = std::string(kHead) + "[grid.uncompressed]\nseed = [1, 2]\n" +
                           "[[points.uncompressed]]\nseed = 3\n";
  const std::string e = parse_error(body);
  EXPECT_NE(e.find("has both a grid and points"), std::string::npos) << e;
  EXPECT_NE(e.find("line "), std::string::npos) << e;
  EXPECT_EQ(e.find("line 0"), std::string::npos) << e;
  // The same with the points in a variant: the file and the variant together have both.
  const std::string v = std::string(kHead) + "[grid.uncompressed]\nseed = [1, 2]\n" +
                        "[variant.quick]\npoints = { uncompressed = [{ seed = 3 }] }\n";
  EXPECT_NE(parse_error(v, "quick").find("has both a grid and points"), std::string::npos);
}

TEST_F(ExperimentOutcome, PointsAreCountedAndAHugeGridIsRefusedBeforeItRuns) {
  const auto f = write(
      "big.toml",
      "name = \"big\"\nkind = \"sweep\"\nscenes = "
      "[\"tiny-sphere-plane\", \"bunny\"]\nbackends = [\"haar\", "
      "\"uncompressed\"]\n[grid.haar]\nk = [" +
          [] {
            std::string s;
            for (int i = 1; i <= 1000; ++i) s += (i > 1 ? ", " : "") + std::to_string(i);
            return s;
          }() +
          "]\nmax_terms = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9]\n");
  const ExperimentSpec spec = parse(f);
  EXPECT_EQ(points_per_scene(spec), 1000u * 10u + 1u);
  EXPECT_EQ(planned_points(spec), 2u * 10001u);
  try {
    check_point_budget(spec, kDefaultMaxPoints);
    ADD_FAILURE() << "a 20,002-point grid passed the default budget";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("big.toml"), std::string::npos) << what;
    EXPECT_NE(what.find("20002 points"), std::string::npos) << what;
    EXPECT_NE(what.find("--max-points"), std::string::npos) << what;
  }
  EXPECT_NO_THROW(check_point_budget(spec, 20002));
  // run_experiment refuses it too, before any folder exists.
  EXPECT_THROW(run_experiment(spec, options()), InputError);
  EXPECT_FALSE(fs::exists(dir_ / "results"));
  // The repository's own files fit the default.
  for (const auto& file : experiment_files()) {
    const std::string kind = declared_kind(file);
    if (kind == "material_table" || kind == "stability") continue;
    for (const std::string& variant : [&] {
           auto v = experiment_variants(file);
           v.insert(v.begin(), "");
           return v;
         }()) {
      const auto s = parse_experiment(file, variant, CompressorRegistry::instance().names());
      EXPECT_LE(planned_points(s), kDefaultMaxPoints) << file << " " << variant;
    }
  }
}

TEST_F(ExperimentOutcome, TheCountIsTheNumberOfPointsARunMeasures) {
  const auto f = write("sweep.toml", std::string(kHead) +
                                         "images = false\ntiming = false\n"
                                         "[grid.uncompressed]\nseed = [1, 2, 3]\n");
  const ExperimentSpec spec = parse(f);
  ASSERT_EQ(planned_points(spec), 3u);
  std::vector<std::string> lines;
  RunOptions o = options();
  o.on_progress = [&](const std::string& l) { lines.push_back(l); };
  const RunSummary s = run_experiment(spec, o);
  EXPECT_EQ(s.points, 3u);
  EXPECT_EQ(s.failed, 0u);
  EXPECT_TRUE(s.complete);
  ASSERT_FALSE(lines.empty());
  EXPECT_NE(lines.front().find("3 points"), std::string::npos) << lines.front();
}

TEST_F(ExperimentOutcome, AnEnvironmentThatIsNotAMapFailsBeforeAnyStage) {
  const fs::path bad = write("notamap.exr", "not an exr");
  const auto f =
      write("env.toml", std::string(kHead) + "environments = [\"" + bad.string() + "\"]\n");
  const ExperimentSpec spec = parse(f);  // the file exists: the parser accepts the name
  try {
    (void)run_experiment(spec, options());
    ADD_FAILURE() << "ran with an unreadable environment map";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("env.toml"), std::string::npos) << what;
    EXPECT_NE(what.find("notamap"), std::string::npos) << what;
    EXPECT_NE(what.find("not a readable map"), std::string::npos) << what;
  }
  EXPECT_FALSE(fs::exists(dir_ / "results")) << "a folder was written before the check";
  EXPECT_FALSE(fs::exists(dir_ / "cache" / "transfer")) << "a stage ran before the check";
}

TEST_F(ExperimentOutcome, ARunWhereEveryPointFailedIsNotComplete) {
  const auto f = write("fails.toml", "name = \"fails\"\nkind = \"sweep\"\nscenes = [\"" +
                                         broken_scene().string() +
                                         "\"]\nbackends = [\"uncompressed\"]\nimages = false\n");
  const RunSummary s = run_experiment(parse(f), options());
  EXPECT_EQ(s.points, 0u);
  EXPECT_EQ(s.failed, 1u);
  EXPECT_FALSE(s.complete);
  EXPECT_NE(s.first_failure.find("broken"), std::string::npos) << s.first_failure;
  EXPECT_FALSE(fs::exists(s.folder / ".complete"));
  EXPECT_TRUE(fs::exists(s.folder / ".started"));
  // The failure is recorded in the result (the CLI's report turns it into README.md).
  ASSERT_TRUE(fs::exists(s.folder / "result.json"));
  const auto result = nlohmann::json::parse(std::ifstream(s.folder / "result.json"));
  EXPECT_EQ(result.at("failures").size(), 1u);
}

TEST_F(ExperimentOutcome, AMissingSceneIsNamedBeforeTheCompleteFolder) {
  const auto f = write("gone.toml", std::string(kHead) + "images = false\ntiming = false\n");
  ExperimentSpec spec = parse(f);
  RunOptions o = options();
  ASSERT_TRUE(run_experiment(spec, o).complete);
  spec.scenes = {"no-such-scene"};
  spec.name = "x";  // the same, complete folder
  try {
    (void)run_experiment(spec, o);
    ADD_FAILURE() << "ran a missing scene";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("no-such-scene"), std::string::npos) << what;
    EXPECT_EQ(what.find("--force"), std::string::npos) << what;
  }
}

TEST_F(ExperimentOutcome, FailedPointsMakeTheCommandFailWithOneLineEvenQuiet) {
  const std::string env = "PRTLAB_CACHE=\"" + (dir_ / "cache").string() + "\" ";
  const auto f = write("partly.toml",
                       "name = \"partly\"\nkind = \"sweep\"\nscenes = "
                       "[\"tiny-sphere-plane\", \"" +
                           broken_scene().string() +
                           "\"]\nbackends = [\"uncompressed\"]\nimages = false\n"
                           "timing = false\n");
  const auto out = dir_ / "results";
  const auto r = run_cli("-q --no-opencl experiment run \"" + f.string() + "\" --no-plot --out \"" +
                             out.string() + "\"",
                         dir_, env);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("1 point failed, 1 measured"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("broken"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(out / "partly" / ".complete"));  // some points were measured
  // A planned count over --max-points is refused before the device opens.
  const auto big = run_cli("-q --no-opencl experiment run \"" + f.string() +
                               "\" --no-plot --max-points 1 --out \"" + out.string() + "\"",
                           dir_, env);
  EXPECT_EQ(big.exit_code, 1);
  EXPECT_NE(big.err.find("2 points"), std::string::npos) << big.err;
  // A malformed --device-param is named as such.
  const auto dp = run_cli(
      "-q --no-opencl compress tiny-sphere-plane --backend uncompressed "
      "--device-param oops",
      dir_, env);
  EXPECT_NE(dp.exit_code, 0);
  EXPECT_NE(dp.err.find("--device-param 'oops': expected key=value"), std::string::npos) << dp.err;
}

}  // namespace
}  // namespace prt::experiments
