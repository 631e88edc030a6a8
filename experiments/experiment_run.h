#pragma once
// `prtlab experiment run <file>`: an experiment file (experiment_spec.h) turned into one result
// folder (docs/experiments.md "Result folders"):
//
//   <out>/<name>[-<variant>]/
//     result.json   everything: the spec, provenance, scenes, searches, points (with their
//                   per-environment errors), cache statistics
//     points.csv    one row per point, fixed columns (point_record_columns(), after experiment
//                   and variant)
//     errors.csv    one row per point, environment and view
//     images/       PNGs of the kept images (equal storage) and their false-colour error maps
//     .complete     written last: the folder holds a finished run
//
// Computing and reporting are separate: run_experiment() writes the files above;
// write_experiment_report() (experiment_report.h) reads result.json and writes README.md and
// the plots, so a report can be redrawn without recomputing.
//
// A folder without .complete is an interrupted run: running again resumes it (every point is a
// cached stage, so finished points load in milliseconds) and gives the same files. A complete
// folder is never overwritten without `force`.
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "experiment_spec.h"
#include "prtlab/storage/stage_cache.h"
#include "run_plan.h"

namespace prt {
class ClContext;
class Communicator;
}  // namespace prt

namespace prt::experiments {

struct RunOptions {
  std::filesystem::path out_root = "results";       ///< the folder goes to out_root/<name>
  bool force = false;                               ///< overwrite a complete result folder
  bool recompute = false;                           ///< recompute every stage (cache refresh)
  ClContext* device = nullptr;                      ///< OpenCL timings and rendering; null: C++
  std::optional<std::filesystem::path> cache_root;  ///< default prt::cache_dir()
  std::vector<std::string> scenes;                  ///< replace the spec's scenes when not empty
  bool show_progress_bars = true;                   ///< the stages' progress bars
  std::string command_line;                         ///< recorded in the provenance
  /// A file planning more points than this is refused before anything runs (run_plan.h).
  std::size_t max_points = kDefaultMaxPoints;
  /// A line per point and stage, with an ETA ("[fig6 3/7, ETA 1m40s] bunny csr_zstd: ...").
  std::function<void(const std::string&)> on_progress;
  /// For tests: stop (throw RunInterrupted) after measuring this many points, as a killed run
  /// would. 0: never.
  int stop_after_points = 0;
  /// Spread the points over these ranks (docs/distributed.md; collective: every rank calls with
  /// the same spec and options). Null or one rank: this process alone.
  Communicator* comm = nullptr;
};

/// Thrown by run_experiment when RunOptions::stop_after_points is reached.
struct RunInterrupted : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct RunSummary {
  std::filesystem::path folder;
  nlohmann::json result;      ///< what result.json holds
  bool resumed = false;       ///< the folder held an interrupted run
  std::size_t points = 0;     ///< points measured
  std::size_t failed = 0;     ///< points (or scenes) that failed, each in result.json "failures"
  std::string first_failure;  ///< "scene point: error" of the first failure, for one-line summaries
  bool complete = false;      ///< .complete written: false when every point failed
  int ranks = 1;              ///< processes the points were measured on
};

/// The result folder `spec` writes under `out_root`.
std::filesystem::path result_folder(const ExperimentSpec& spec,
                                    const std::filesystem::path& out_root);

/// Run the experiment and write its result files (not the report). Throws ParameterError when
/// the folder holds a complete run and !force, and InputError when an environment map it names
/// cannot be read (both before any stage runs). A point that fails is recorded (failures in
/// result.json and the README) and the run goes on; a run where every point failed writes its
/// files but not .complete. Callers report `failed` (the CLI exits non-zero).
RunSummary run_experiment(const ExperimentSpec& spec, const RunOptions& options);

}  // namespace prt::experiments
