#pragma once
// `prtlab experiment stability`: an experiment of kind "stability" (docs/experiments.md
// "Stability suite"). Every case feeds every registered transfer backend, material or loader it
// applies to an input that breaks numerics (float accumulation on large scenes, a sun 1e5 times
// the sky, radiance near float's range, NaN and Inf in lights, meshes and BTFs, degenerate
// triangles, vertices that see nothing, CPCA clusters smaller than n' or empty, ill-conditioned
// SRBF Gram systems, the hemispherical projection near A's smallest singular value) and records
// what happened:
//
//   ok       finite result, within the declared bound (the error reached is reported)
//   warned   the failure mode was detected and reported with a named warning (which ones)
//   refused  a named error (InputError, ParameterError or NumericalError) stopped the input
//   silent   a non-finite or out-of-bound result with no warning and no error: a defect
//   crashed  an exception that is not one of prtlab's errors: a defect
//
//   <out>/<name>[-<variant>]/
//     result.json   the spec, provenance, one row per (case, subject)
//     cases.csv     the rows
//     README.md     the table, silent cases first
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace prt::experiments {

/// Whether `file` declares kind = "stability" (false when it cannot be read).
bool is_stability_suite(const std::filesystem::path& file);

/// The variants the file declares ([variant.<name>] tables), sorted.
std::vector<std::string> stability_suite_variants(const std::filesystem::path& file);

/// Parses `file` with `variant` applied and validates it (InputError naming the file); runs
/// nothing.
void check_stability_suite(const std::filesystem::path& file, const std::string& variant);

/// out_root / <name>[-<variant>].
std::filesystem::path stability_suite_folder(const std::filesystem::path& file,
                                             const std::string& variant,
                                             const std::filesystem::path& out_root);

/// The cases the suite knows, in report order.
const std::vector<std::string>& stability_case_names();

struct StabilityOptions {
  std::filesystem::path out_root = "results";
  std::string variant;             ///< "quick" or "" (the file's top level)
  std::vector<std::string> cases;  ///< only these cases (empty: the file's)
  std::string command_line;
  bool show_progress = true;
};

/// Runs the file and writes its folder; returns result.json's content with "folder". Throws an
/// Error naming the silent and crashed rows after writing the folder, so that a defect fails
/// the command (and CI) while its report stays readable.
nlohmann::json run_stability_suite(const std::filesystem::path& file,
                                   const StabilityOptions& options);

}  // namespace prt::experiments
