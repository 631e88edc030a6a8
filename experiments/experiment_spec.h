#pragma once
// An experiment as a file: experiments/<name>.toml (docs/experiments.md "Experiment files").
//
// The file names the scenes, the backends and their parameter grids, the environments, the
// views, the repeats and what to measure; [variant.quick] and [variant.full] tables override
// any of those keys, so one file holds the seconds-long smoke run and the paper-sized run.
// Parsing validates everything that can be checked without running a stage: unknown keys,
// wrong types, unknown backends and parameters, unknown environments, empty grids. Every error
// names the file and, where toml++ knows it, the line.
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace prt::experiments {

enum class ExperimentKind {
  kEqualStorage,  ///< search every backend's size knob to a target storage (the paper's Fig. 6)
  kSweep,         ///< every point of every backend's grid (run time and storage against error)
};

/// Every `kind` an experiment file may declare: the two parse_experiment() reads and the two
/// that run their own way (material_table.h, stability_suite.h).
const std::vector<std::string>& experiment_kinds();
std::string_view to_string(ExperimentKind k);

/// One environment of the evaluation: a lat-long EXR by name or path, or a procedural sun and
/// sky ("sun:RATIO") whose sun is RATIO times brighter than the sky, or the sun alone
/// ("sunonly:RATIO", every cube face but the sun's black: what face skipping is for).
struct EnvironmentSpec {
  std::string name;  ///< as reported ("courtyard", "sun-1e+04")
  std::string file;  ///< resolved EXR path; empty for the procedural sun
  std::optional<double> sun_ratio;
  bool sun_only = false;  ///< "sunonly:RATIO": sky and ground black, only the sun's faces lit
};

struct TargetSpec {
  std::string backend = "bicluster";          ///< the target is this backend's storage ...
  std::map<std::string, std::string> params;  ///< ... at these parameters
  std::optional<double> megabytes;            ///< or a fixed target, 1e6 bytes
  double tolerance = 0.05;                    ///< |storage / target - 1| to reach
  int max_probes = 14;                        ///< compressions a search may spend per backend
};

/// A plot of a sweep (docs/experiments.md "Curves"): one backend's points, `y` (a points.csv
/// column, or metrics.<name>: a backend metric) against the parameter `x`, one line per value of
/// the parameter `series`, one panel per value of `panel` (optional). The CPCA paper's Fig. 2/3 are
/// such curves.
struct CurveSpec {
  std::string backend;
  std::string x;
  std::string y = "frobenius_se";
  std::string series;  ///< empty: one line
  std::string panel;   ///< empty: one panel
  bool log_x = false;
  bool log_y = false;
  std::string title;
};

struct ExperimentSpec {
  std::filesystem::path file;
  std::string name;     ///< the result folder: results/<name>[-<variant>]/
  std::string title;    ///< heading of the report
  std::string variant;  ///< "quick" or "full" (empty: the file's top level)
  ExperimentKind kind = ExperimentKind::kSweep;
  std::vector<std::string> scenes;
  /// Per-scene settings swept as scene variants (the paper's Fig. 8: local_grid = [8, ...]);
  /// one derived scene per value (scene_variants.h).
  std::map<std::string, std::vector<std::int64_t>> scene_grid;
  std::vector<std::string> backends;  ///< resolved: registered names, in registry order
  std::vector<std::string> exclude;
  std::map<std::string, std::map<std::string, std::string>> params;  ///< fixed, per backend
  /// Values swept per backend and key; a backend without a grid sweeps its size knob at
  /// `knob_points` values (or is measured once when it has none).
  std::map<std::string, std::map<std::string, std::vector<std::string>>> grid;
  /// Explicit points per backend (`[[points.<backend>]]` tables), each over the fixed params;
  /// a backend has either a grid or points.
  std::map<std::string, std::vector<std::map<std::string, std::string>>> points;
  std::vector<CurveSpec> curves;
  int knob_points = 5;
  std::vector<EnvironmentSpec> environments;
  std::vector<std::string> views;  ///< scene view presets; empty: the scene's first
  int width = 256;
  int height = 192;
  /// The synthetic BTFs the frame loop shades with (texels per side, view_side^2 views); the
  /// light side is always the scene's local grid. Large local grids need fewer texels: the raw
  /// BTF holds texels^2 x views x M floats per colour.
  int btf_resolution = 32;
  int btf_view_side = 12;
  int repeats = 10;  ///< timed relights per point (median)
  /// Relights of the harness's Frobenius error of T per point; 0 skips it (the frobenius_*
  /// columns are then empty), for experiments whose error is a backend metric.
  int frobenius_relights = 64;
  bool timing = true;                      ///< false: no timings (deterministic results, for tests)
  bool images = true;                      ///< render images and image errors
  bool fps = false;                        ///< time view-change and light-change frames per point
  int fps_frames = 10;                     ///< frames per loop
  std::string reference = "uncompressed";  ///< the exact image and relight comparison
  TargetSpec target;                       ///< kEqualStorage only
  /// Numbers of the papers to print beside ours, keyed by backend: free text rows
  /// ("32 clusters x 8 vectors = 36.2 MB").
  std::map<std::string, std::string> paper;
  std::string paper_source;  ///< where those numbers come from
};

/// An environment as experiment files name it ("courtyard", a Blender world; "sun:3e4",
/// "sunonly:3e4", the procedural sun), resolved to its EXR; `file` names the file asking, for
/// the error.
EnvironmentSpec parse_environment(const std::filesystem::path& file, const std::string& name);

/// What a point's numbers depend on besides its backend and parameters: environments, views,
/// image size, repeats, timing, images, fps, reference (part of every point's cache key).
nlohmann::json evaluation_json(const ExperimentSpec& spec);
/// The whole parsed spec (result.json's "experiment").
nlohmann::json to_json(const ExperimentSpec& spec);

/// The `kind` a file declares ("" when it has none or cannot be read: the caller's own parser
/// then reports the problem). Kinds with their own runner (material tables, the stability suite)
/// dispatch on it.
std::string declared_kind(const std::filesystem::path& file);
/// The [variant.<name>] tables a file declares, sorted (empty when it cannot be read).
std::vector<std::string> declared_variants(const std::filesystem::path& file);

/// The variants a file declares ("full", "quick"), sorted by name.
std::vector<std::string> experiment_variants(const std::filesystem::path& file);

/// Parse `file` with `variant` applied ("" = the top level; an unknown variant is an InputError
/// listing the declared ones). `registered` are the backend names that exist now (a --plugin's
/// included): "*" in `backends` expands to them.
ExperimentSpec parse_experiment(const std::filesystem::path& file, const std::string& variant,
                                const std::vector<std::string>& registered);

/// An experiment by name (experiments/<name>.toml, compressors/*/experiments/<name>.toml) or a
/// path. InputError listing the known names when none matches.
std::filesystem::path resolve_experiment(const std::string& name_or_path);

/// Every experiment file the repository holds: experiments/*.toml, then each backend folder's
/// experiments/*.toml, sorted within each group.
std::vector<std::filesystem::path> experiment_files();

}  // namespace prt::experiments
