// Experiment files run end to end on the tiny scene (experiments/experiment_run.h): the
// equal-storage search on a backend with a storage curve known in closed form, resuming an
// interrupted run, refusing to overwrite, the stage cache on a repeated run, and the parser's
// refusals.
#include "experiment_run.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "experiment_report.h"
#include "experiment_spec.h"
#include "material_table.h"
#include "plot_script.h"
#include "point_measurement.h"
#include "prtlab/base/error.h"
#include "prtlab/compress/backend_input.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/geometry/scene.h"
#include "prtlab/storage/data_paths.h"
#include "stability_suite.h"
#include "support/temp_dir.h"

namespace prt::experiments {
namespace {
namespace fs = std::filesystem;
using json = nlohmann::json;

std::string read(const fs::path& f) {
  std::ifstream in(f);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A CSV without its provenance comment lines (dates and commands differ between runs).
std::string csv_body(const fs::path& f) {
  std::string out, line;
  std::ifstream in(f);
  while (std::getline(in, line))
    if (!line.starts_with("#")) out += line + "\n";
  return out;
}

json points_without_times(const fs::path& folder) {
  json points = json::parse(read(folder / "result.json")).at("points");
  for (auto& p : points) p.erase("measure_seconds");
  return points;
}

class ExperimentRun : public ::testing::Test {
 protected:
  fs::path write_spec(const std::string& name, const std::string& body) {
    const fs::path f = dir_ / (name + ".toml");
    std::ofstream(f) << body;
    return f;
  }
  ExperimentSpec parse(const fs::path& f, const std::string& variant = "") {
    return parse_experiment(f, variant, CompressorRegistry::instance().names());
  }
  RunOptions options(const std::string& tag) {
    RunOptions o;
    o.out_root = dir_ / ("results-" + tag);
    o.cache_root = dir_ / ("cache-" + tag);
    o.show_progress_bars = false;
    return o;
  }
  prt::testing::TempDir tmp_{"experiment_run"};
  fs::path dir_ = tmp_.path();
};

// The deterministic sweep the resume tests run: no timings, so two runs give the same files.
const char* kSweep = R"(
name = "tiny-sweep"
kind = "sweep"
scenes = ["tiny-sphere-plane"]
backends = ["bicluster", "coo", "uncompressed"]
environments = ["courtyard", "sun:1e4"]
image = { width = 48, height = 36 }
timing = false
knob_points = 3
[grid.bicluster]
error = [0, 0.05]
)";

TEST_F(ExperimentRun, EqualStorageLandsWithinFivePercentOnAKnownStorageCurve) {
  // coo keeps ceil(keep * n_r) entries of each row r at 12 bytes each: the target is that curve
  // at keep = 0.37, computed here from T alone.
  StageCache cache(dir_ / "cache-curve");
  const SceneDesc desc = parse_scene(resolve_scene("tiny-sphere-plane"));
  const std::vector<std::string> coo = {"coo"};
  const PreparedScene scene = prepare_scene_for(desc, coo, cache, {.show_progress = false});
  const TransferMatrix& t = scene.transfer.result.transfer;
  std::uint64_t entries = 0;
  for (std::size_t r = 0; r < t.rows(); ++r) {
    const auto n = t.row_offsets()[r + 1] - t.row_offsets()[r];
    entries += static_cast<std::uint64_t>(std::ceil(0.37 * static_cast<double>(n)));
  }
  const std::uint64_t target = 12 * entries;
  const auto f = write_spec("curve", fmt::format(R"(
name = "curve"
kind = "equal_storage"
scenes = ["tiny-sphere-plane"]
backends = ["coo"]
images = false
timing = false
[target]
megabytes = {}
tolerance = 0.05
)",
                                                 static_cast<double>(target) / 1e6));
  RunOptions o = options("curve");
  o.cache_root = dir_ / "cache-curve";
  const RunSummary s = run_experiment(parse(f), o);
  ASSERT_EQ(s.result.at("points").size(), 1u);
  const json& p = s.result.at("points")[0];
  EXPECT_TRUE(p.at("reached").get<bool>());
  EXPECT_LE(std::abs(p.at("storage_ratio").get<double>() - 1.0), 0.05);
  // The reported storage is the curve's at the value found.
  const double keep = std::stod(p.at("knob_value").get<std::string>());
  std::uint64_t at_keep = 0;
  for (std::size_t r = 0; r < t.rows(); ++r) {
    const auto n = t.row_offsets()[r + 1] - t.row_offsets()[r];
    at_keep += static_cast<std::uint64_t>(std::ceil(keep * static_cast<double>(n)));
  }
  EXPECT_EQ(p.at("storage_bytes").get<std::uint64_t>(), 12 * at_keep);
  // SE = ||T~ - T||_F^2 is the squared norm of the entries coo drops: each row's smallest
  // n - ceil(keep n) values (ties are equal values, so which of them go does not matter).
  double dropped_sq = 0;
  for (std::size_t r = 0; r < t.rows(); ++r) {
    std::vector<double> v;
    for (auto i = t.row_offsets()[r]; i < t.row_offsets()[r + 1]; ++i) v.push_back(t.value(i));
    std::sort(v.begin(), v.end(), std::greater<>());
    const auto kept = static_cast<std::size_t>(std::ceil(keep * static_cast<double>(v.size())));
    for (std::size_t q = kept; q < v.size(); ++q) dropped_sq += v[q] * v[q];
  }
  // The relative error is exact or Hutchinson's estimate (then within three standard errors).
  const double rel = p.at("frobenius_rel").get<double>();
  const double se_stderr =
      2 * rel * p.at("frobenius_stderr").get<double>() * dropped_sq / (rel * rel);
  EXPECT_NEAR(p.at("frobenius_se").get<double>(), dropped_sq, 3 * se_stderr + 1e-6 * dropped_sq);
  EXPECT_EQ(p.at("frobenius_exact").get<bool>(), p.at("frobenius_stderr").get<double>() == 0);
  const json& search = s.result.at("searches")[0];
  EXPECT_TRUE(search.at("reached").get<bool>());
  EXPECT_LE(search.at("probes").size(), 14u);
  EXPECT_TRUE(fs::exists(s.folder / ".complete"));
  // The report of an untimed, imageless run renders (no timing, no PSNR: n/a, never NaN).
  write_experiment_report(s.folder, false, true);
  const std::string md = read(s.folder / "README.md");
  EXPECT_NE(md.find("| `coo` |"), std::string::npos) << md;
  EXPECT_EQ(md.find(" nan"), std::string::npos)
      << md.substr(std::min(md.size(), md.find(" nan")), 80);
}

TEST_F(ExperimentRun, ForceReplacesOnlyWhatTheRunWrote) {
  // An equal-storage run with images, then a forced run without one of its backends: the
  // dropped backend's images go, a file the user put into the folder stays, and the folder is
  // complete again.
  const char* body = R"(
name = "force"
kind = "equal_storage"
scenes = ["tiny-sphere-plane"]
backends = [%s]
environments = ["courtyard"]
image = { width = 32, height = 24 }
timing = false
[params.bicluster]
error = 0
)";
  const auto spec_with = [&](const std::string& backends) {
    std::string text = body;
    text.replace(text.find("%s"), 2, backends);
    return parse(write_spec("force", text));
  };
  RunOptions o = options("force");
  const RunSummary first = run_experiment(spec_with("\"bicluster\", \"uncompressed\""), o);
  const fs::path folder = first.folder;
  const auto image_of = [&](const std::string& backend) {
    return folder / "images" / ("tiny-sphere-plane-courtyard-front-" + backend + ".png");
  };
  ASSERT_TRUE(fs::exists(image_of("uncompressed")));
  std::ofstream(folder / "notes.txt") << "mine";
  o.force = true;
  const RunSummary second = run_experiment(spec_with("\"bicluster\""), o);
  EXPECT_TRUE(fs::exists(image_of("bicluster")));
  EXPECT_FALSE(fs::exists(image_of("uncompressed")));
  EXPECT_TRUE(fs::exists(folder / "notes.txt"));
  EXPECT_TRUE(fs::exists(folder / ".complete"));
  EXPECT_EQ(second.result.at("points").size(), 1u);
  // The equal-storage report names the target and the backend.
  write_experiment_report(folder, false, true);
  const std::string md = read(folder / "README.md");
  EXPECT_NE(md.find("at equal storage"), std::string::npos);
  EXPECT_NE(md.find("Only `bicluster` reached"), std::string::npos) << md;
}

TEST_F(ExperimentRun, ResumingAnInterruptedRunGivesTheSameFiles) {
  const auto f = write_spec("sweep", kSweep);
  const ExperimentSpec spec = parse(f);

  const RunSummary whole = run_experiment(spec, options("whole"));
  const std::size_t points = whole.result.at("points").size();
  ASSERT_EQ(points, 2u + 3u + 1u);  // bicluster grid, coo knob at 3 values, uncompressed

  RunOptions o = options("resumed");
  o.stop_after_points = 2;
  EXPECT_THROW(run_experiment(spec, o), RunInterrupted);
  const fs::path folder = result_folder(spec, o.out_root);
  EXPECT_FALSE(fs::exists(folder / ".complete"));
  EXPECT_TRUE(fs::exists(folder / ".started"));
  o.stop_after_points = 0;
  const RunSummary resumed = run_experiment(spec, o);
  EXPECT_TRUE(resumed.resumed);
  EXPECT_EQ(resumed.result.at("cache").at("points_from_cache").get<int>(), 2);
  EXPECT_EQ(resumed.result.at("cache").at("points_computed").get<int>(),
            static_cast<int>(points) - 2);

  EXPECT_EQ(csv_body(whole.folder / "points.csv"), csv_body(resumed.folder / "points.csv"));
  EXPECT_EQ(csv_body(whole.folder / "errors.csv"), csv_body(resumed.folder / "errors.csv"));
  EXPECT_EQ(points_without_times(whole.folder), points_without_times(resumed.folder));
  EXPECT_TRUE(fs::exists(resumed.folder / ".complete"));
  EXPECT_FALSE(fs::exists(resumed.folder / ".started"));
}

TEST_F(ExperimentRun, ARepeatedRunLoadsEveryPointAndRefusesToOverwrite) {
  const auto f = write_spec("sweep", kSweep);
  const ExperimentSpec spec = parse(f);
  RunOptions o = options("repeat");
  const RunSummary first = run_experiment(spec, o);
  EXPECT_EQ(first.result.at("cache").at("points_from_cache").get<int>(), 0);
  try {
    run_experiment(spec, o);
    ADD_FAILURE() << "overwrote a complete run";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("--force"), std::string::npos) << e.what();
  }
  o.force = true;
  const RunSummary second = run_experiment(spec, o);
  const json& c = second.result.at("cache");
  EXPECT_EQ(c.at("points_from_cache").get<int>(),
            static_cast<int>(first.result.at("points").size()));
  EXPECT_EQ(c.at("points_computed").get<int>(), 0);
  EXPECT_GT(c.at("seconds_saved").get<double>(), 0.0);
  EXPECT_EQ(csv_body(first.folder / "points.csv"), csv_body(second.folder / "points.csv"));

  // The report is drawn from result.json alone.
  write_experiment_report(second.folder, false, true);
  const std::string md = read(second.folder / "README.md");
  EXPECT_NE(md.find("## tiny-sphere-plane"), std::string::npos);
  EXPECT_NE(md.find("`coo`"), std::string::npos);
}

TEST_F(ExperimentRun, EveryPointHasTheFixedColumns) {
  const auto f = write_spec("sweep", kSweep);
  const RunSummary s = run_experiment(parse(f), options("columns"));
  std::ifstream in(s.folder / "points.csv");
  std::string line, header;
  while (std::getline(in, line))
    if (!line.starts_with("#")) {
      header = line;
      break;
    }
  std::string expected = "experiment,variant";
  for (const auto& c : point_record_columns()) expected.append(",").append(c);
  EXPECT_EQ(header, expected);
  for (const auto& p : s.result.at("points")) {
    for (const auto& c : point_record_columns()) EXPECT_TRUE(p.contains(c)) << c;
    EXPECT_EQ(p.at("errors").size(), 2u);  // two environments, one view
    // A lossless backend's L* error is float rounding only.
    if (p.at("backend") == "uncompressed") {
      EXPECT_LT(p.at("lstar_rel_l2_mean").get<double>(), 1e-6);
      EXPECT_EQ(p.at("image_rel_l2_mean").get<double>(), 0.0);
    }
  }
}

TEST_F(ExperimentRun, TheParserNamesTheFileAndTheProblem) {
  const auto expect_error = [&](const std::string& body, const std::string& needle,
                                const std::string& variant = "") {
    const auto f = write_spec("bad", body);
    try {
      (void)parse(f, variant);
      ADD_FAILURE() << "accepted: " << body;
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("bad.toml"), std::string::npos) << what;
      EXPECT_NE(what.find(needle), std::string::npos) << what;
    }
  };
  expect_error("name = \"x\"\nscenes = [\"bunny\"]\nrepeat = 3\n", "unknown key 'repeat'");
  expect_error("name = \"x\"\nscenes = [\"bunny\"]\nbackends = [\"nope\"]\n",
               "backend 'nope' is not registered");
  expect_error("name = \"x\"\nscenes = [\"bunny\"]\n[params.bicluster]\nerorr = 1\n", "erorr");
  expect_error("name = \"x\"\nscenes = [\"bunny\"]\nenvironments = [\"moon\"]\n", "moon");
  expect_error("name = \"x\"\nscenes = [\"bunny\"]\n", "no variant 'quick'", "quick");
  expect_error("name = \"X Y\"\nscenes = [\"bunny\"]\n", "lower-case");
  expect_error("name = \"x\"\nscenes = [\"bunny\"]\nkind = \"fast\"\n", "kind 'fast'");
  expect_error("name = \"x\"\nscenes = [\"bunny\"]\nimage = { width = 2 }\n", "image.width");
  expect_error("name = \"x\"\nscenes = [\"bunny\"]\nscene_grid = { colour = [1] }\n", "colour");
  expect_error("name = \"x\"\nscenes = [\"bunny\"\n", "line");
  expect_error("name = \"x\"\nscenes = [\"bunny\"]\nkind = \"equal_storage\"\ntarget = 36.4\n",
               "'target' must be a table");
  expect_error("name = \"x\"\nscenes = [\"bunny\"]\nenvironments = [\"sun:100\", \"sun:1e2\"]\n",
               "listed twice");
  expect_error("name = \"x\"\nscenes = [\"bunny\"]\nscene_grid = { local_grid = [8, 100] }\n",
               "local_grid");
  expect_error(
      "name = \"x\"\nscenes = [\"bunny\"]\nkind = \"equal_storage\"\n[target]\n"
      "params = { eror = 1 }\n",
      "eror");
  expect_error("name = \"x\"\nscenes = [\"bunny\"]\n[variant.\"../up\"]\n", "variant '../up'",
               "../up");
}

TEST_F(ExperimentRun, VariantsReplaceTheKeysTheyName) {
  const auto f = write_spec("variants", R"(
name = "v"
scenes = ["bunny"]
repeats = 10
environments = ["blender", "sun"]
[variant.quick]
scenes = ["tiny-sphere-plane"]
repeats = 2
)");
  EXPECT_EQ(experiment_variants(f), (std::vector<std::string>{"quick"}));
  const auto top = parse(f);
  EXPECT_EQ(top.scenes, (std::vector<std::string>{"bunny"}));
  EXPECT_EQ(top.environments.size(), 9u);  // the eight Blender worlds and the sun
  EXPECT_EQ(top.environments.back().name, "sun-30000");
  const auto quick = parse(f, "quick");
  EXPECT_EQ(quick.scenes, (std::vector<std::string>{"tiny-sphere-plane"}));
  EXPECT_EQ(quick.repeats, 2);
  EXPECT_EQ(quick.environments.size(), 9u);
  EXPECT_EQ(result_folder(quick, "r"), fs::path("r") / "v-quick");
  // "*" is every registered backend.
  EXPECT_EQ(top.backends, CompressorRegistry::instance().names());
}

// Explicit [[points]] are measured as listed (and nothing else), [[curves]] reach result.json,
// the plot and the report, and frobenius_se_declared is the backend's exact squared error.
TEST_F(ExperimentRun, ExplicitPointsAndCurves) {
  const auto f = write_spec("curves", R"(
name = "tiny-curves"
kind = "sweep"
scenes = ["tiny-sphere-plane"]
backends = ["cpca"]
environments = ["courtyard"]
images = false
timing = false
[[points.cpca]]
clusters = 2
vectors = 0
[[points.cpca]]
clusters = 4
vectors = 1
method = "static"
[[curves]]
backend = "cpca"
x = "clusters"
y = "frobenius_se_declared"
series = "vectors"
log_y = true
[[curves]]
backend = "cpca"
x = "storage_mb"
y = "frobenius_se_declared"
)");
  const ExperimentSpec spec = parse(f);
  ASSERT_EQ(spec.points.at("cpca").size(), 2u);
  ASSERT_EQ(spec.curves.size(), 2u);
  EXPECT_EQ(spec.curves[1].x, "storage_mb");
  EXPECT_EQ(spec.curves[0].series, "vectors");
  const RunSummary s = run_experiment(spec, options("curves"));
  const json& points = s.result.at("points");
  ASSERT_EQ(points.size(), 2u);
  for (const auto& p : points) {
    const double declared = p.at("frobenius_se_declared").get<double>();
    const double measured = p.at("frobenius_se").get<double>();
    // se = rel^2 ||T||^2, so its standard error is 2 stderr(rel) se / rel.
    const double stderr_se =
        2 * p.at("frobenius_stderr").get<double>() * measured / p.at("frobenius_rel").get<double>();
    EXPECT_GT(declared, 0.0);
    // The harness's estimate agrees with the declared value within its own standard error.
    EXPECT_NEAR(measured, declared, 5 * stderr_se + 1e-3 * declared);
  }
  EXPECT_EQ(s.result.at("experiment").at("curves").size(), 2u);
  write_experiment_report(s.folder, true, true);
  const std::string report = read(s.folder / "README.md");
  EXPECT_NE(report.find("## Curves"), std::string::npos);
  // The curve over a points.csv column tabulates that column's values as its x.
  for (const auto& p : points)
    EXPECT_NE(report.find(fmt::format("{:.4g}", p.at("storage_mb").get<double>())),
              std::string::npos)
        << report;
  if (python_with_matplotlib()) {
    EXPECT_TRUE(fs::exists(s.folder / "curves0-tiny-sphere-plane.png"));
    EXPECT_TRUE(fs::exists(s.folder / "curves1-tiny-sphere-plane.png"));
  }
  // A backend with both a grid and points, and a curve naming no parameter, are refused.
  const auto bad = write_spec("bad", R"(
name = "x"
scenes = ["bunny"]
[grid.cpca]
vectors = [1, 2]
[[points.cpca]]
vectors = 3
)");
  EXPECT_THROW(parse(bad), InputError);
  const auto bad2 = write_spec("bad2", R"(
name = "x"
scenes = ["bunny"]
[[curves]]
backend = "cpca"
x = "colour"
)");
  EXPECT_THROW(parse(bad2), InputError);
  // Only x may name a points.csv column: a series must be a parameter.
  const auto bad3 = write_spec("bad3", R"(
name = "x"
scenes = ["bunny"]
[[curves]]
backend = "cpca"
x = "clusters"
series = "storage_mb"
)");
  EXPECT_THROW(parse(bad3), InputError);
}

// What a backend measures of itself (CompressedTransfer::backend_metrics(); the test backend
// coo reports entries_kept, which its storage fixes: 12 bytes per triplet) reaches result.json,
// points.csv and the report, and a curve plots it as metrics.<name>; a backend that declares
// none leaves the column empty.
TEST_F(ExperimentRun, BackendMetricsReachEveryResultFile) {
  const auto f = write_spec("metrics", R"(
name = "tiny-metrics"
kind = "sweep"
scenes = ["tiny-sphere-plane"]
backends = ["coo", "uncompressed"]
environments = ["courtyard"]
images = false
timing = false
frobenius_relights = 0
[grid.coo]
keep = [0.25, 0.5]
[[curves]]
backend = "coo"
x = "keep"
y = "metrics.entries_kept"
[[curves]]
backend = "coo"
x = "metrics.entries_kept"
y = "frobenius_se_declared"
)");
  const RunSummary s = run_experiment(parse(f), options("metrics"));
  const json& points = s.result.at("points");
  ASSERT_EQ(points.size(), 3u);
  std::vector<double> kept;
  for (const auto& p : points) {
    if (p.at("backend") == "uncompressed") {
      EXPECT_TRUE(p.at("backend_metrics").is_null());
      continue;
    }
    // frobenius_relights = 0: the harness's Frobenius error is not measured, the declared one is.
    EXPECT_TRUE(p.at("frobenius_rel").is_null());
    EXPECT_TRUE(p.at("frobenius_se").is_null());
    EXPECT_TRUE(p.at("frobenius_se_declared").is_number());
    const double entries = p.at("backend_metrics").at("entries_kept").get<double>();
    EXPECT_EQ(entries * 12, p.at("storage_bytes").get<double>());
    EXPECT_EQ(p.at("backend_metric_meanings").at("entries_kept"), "triplets of T kept");
    kept.push_back(entries);
  }
  ASSERT_EQ(kept.size(), 2u);
  EXPECT_LT(kept[0], kept[1]);
  // points.csv: the object as a JSON cell under its column; empty for uncompressed.
  const std::string csv = csv_body(s.folder / "points.csv");
  for (double k : kept)
    EXPECT_NE(csv.find(fmt::format("\"{{\"\"entries_kept\"\":{}}}\"", json(k).dump())),
              std::string::npos)
        << csv;
  write_experiment_report(s.folder, true, true);
  const std::string report = read(s.folder / "README.md");
  EXPECT_NE(report.find("## Backend metrics"), std::string::npos) << report;
  EXPECT_NE(report.find("`entries_kept`: triplets of T kept"), std::string::npos) << report;
  for (double k : kept) {
    // In the metrics table and as both curves' values.
    EXPECT_NE(report.find(fmt::format("| {:.5g} |", k)), std::string::npos) << report;
    EXPECT_NE(report.find(fmt::format("| {:.4g} |", k)), std::string::npos) << report;
  }
  // An unknown x is still refused; metrics.<name> is not checked before the run (a backend's
  // metrics are known only from its results).
  const auto bad = write_spec("bad-metric", R"(
name = "x"
scenes = ["bunny"]
[[curves]]
backend = "coo"
x = "entries_kept"
)");
  EXPECT_THROW(parse(bad), InputError);
}

// A backend's light options (haar's light_terms, Ng 2003's N) are point parameters that never
// recompress: a sweep over them compresses once, measures each N, names N in the points that
// set it (not in the default's), and curves may plot against it; a bad value is refused by the
// parser, naming the file.
TEST_F(ExperimentRun, LightOptionsArePointParametersThatNeverRecompress) {
  const auto f = write_spec("light", R"(
name = "tiny-light"
kind = "sweep"
scenes = ["tiny-sphere-plane"]
backends = ["haar"]
environments = ["courtyard"]
images = false
timing = false
frobenius_relights = 0
[params.haar]
k = 16
[grid.haar]
light_terms = [0, 8, 64]
[[curves]]
backend = "haar"
x = "light_terms"
y = "lstar_rel_l2_mean"
)");
  const RunSummary s = run_experiment(parse(f), options("light"));
  const json& points = s.result.at("points");
  ASSERT_EQ(points.size(), 3u);
  std::map<std::string, double> error;
  int fresh_compressions = 0;
  for (const auto& p : points) {
    const std::string params = p.at("params").get<std::string>();
    const auto canonical = p.at("canonical_params");
    const std::string n = canonical.contains("light_terms")
                              ? canonical.at("light_terms").get<std::string>()
                              : std::string("0");
    EXPECT_EQ(params.find("light_terms") != std::string::npos, n != "0") << params;
    error[n] = p.at("lstar_rel_l2_mean").get<double>();
    fresh_compressions += !p.at("compress_cache_hit").get<bool>();
  }
  EXPECT_EQ(fresh_compressions, 1);
  ASSERT_EQ(error.size(), 3u);
  // 8 of the light's 384 coefficients: a coarse light, farther from T L than either the 64-term
  // light or the whole light (whose difference is T~'s alone).
  EXPECT_GT(error.at("8"), error.at("64"));
  EXPECT_GT(error.at("8"), error.at("0"));
  EXPECT_NE(error.at("64"), error.at("0"));

  const auto bad = write_spec("bad-light", R"(
name = "x"
kind = "sweep"
scenes = ["tiny-sphere-plane"]
backends = ["haar"]
[grid.haar]
light_terms = [-3]
)");
  try {
    (void)parse(bad);
    FAIL() << "accepted light_terms = -3";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("light options"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(bad.string()), std::string::npos) << e.what();
  }
}

TEST_F(ExperimentRun, TheRepositorysExperimentFilesParse) {
  const auto files = experiment_files();
  std::vector<std::string> names;
  for (const auto& f : files) {
    names.push_back(f.stem().string());
    if (is_material_table(f)) {  // its own kind and parser (material_table.h)
      for (const auto& v : material_table_variants(f))
        EXPECT_NO_THROW(check_material_table(f, v)) << f;
      EXPECT_NO_THROW(check_material_table(f, "")) << f;
      continue;
    }
    if (is_stability_suite(f)) {  // its own kind too (stability_suite.h)
      for (const auto& v : stability_suite_variants(f))
        EXPECT_NO_THROW(check_stability_suite(f, v)) << f;
      EXPECT_NO_THROW(check_stability_suite(f, "")) << f;
      continue;
    }
    for (const auto& v : experiment_variants(f)) EXPECT_NO_THROW((void)parse(f, v)) << f;
    EXPECT_NO_THROW((void)parse(f)) << f;
  }
  for (const char* n : {"fig6", "fig8", "pareto", "btf-table", "stability"})
    EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
}

}  // namespace
}  // namespace prt::experiments
