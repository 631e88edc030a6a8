#pragma once
// `prtlab experiment run btf-table`: an experiment of kind "material_table" (docs/experiments.md
// "Material tables"): every listed material backend and parameter set on every listed BTF, with
// the columns of Suykens et al. 2003's Table 2 (resolution, ABRDF sampling, factorisation time
// per ABRDF, clustering time, BTF / factored / clustered sizes), the errors of each material
// against the full BTF over all samples (compress/material_error.h: relative L2, Suykens 2003's
// average relative error, floored, cosine-weighted and white-light L2), top-view tile images
// under a few light directions (the paper's Fig. 3) and renders of a scene with each material
// beside the full BTF (relative L2 of the HDR image, SSIM and RMSE of the tone-mapped one).
//
//   <out>/<name>[-<variant>]/
//     result.json   the spec, provenance, one row per (BTF, material)
//     table.csv     the rows, fixed columns
//     README.md     the table beside the paper's numbers, the images
//     images/       <btf>-tiles.png (rows: lights; columns: full, then each material),
//                   <scene>-<btf>-<label>.png and ...-error.png
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace prt {
class ClContext;
}

namespace prt::experiments {

/// Whether `file` declares kind = "material_table" (false when it cannot be read: the caller's
/// own parser then reports the problem).
bool is_material_table(const std::filesystem::path& file);

/// The variants a material table declares ([variant.<name>] tables), sorted.
std::vector<std::string> material_table_variants(const std::filesystem::path& file);

/// Parses `file` with `variant` applied and validates it as run_material_table does (InputError
/// naming the file on any problem); runs nothing.
void check_material_table(const std::filesystem::path& file, const std::string& variant);

/// The result folder run_material_table writes: out_root / <name>[-<variant>].
std::filesystem::path material_table_folder(const std::filesystem::path& file,
                                            const std::string& variant,
                                            const std::filesystem::path& out_root);

struct MaterialTableOptions {
  std::filesystem::path out_root = "results";
  std::string scene;    ///< replaces the file's image scene when not empty
  std::string variant;  ///< "quick" or "" (the file's top level)
  bool force = false;
  ClContext* device = nullptr;  ///< renders on the device when given
  std::string command_line;
  bool show_progress = true;
};

/// Runs the file and writes its folder; returns result.json's content with "folder".
nlohmann::json run_material_table(const std::filesystem::path& file,
                                  const MaterialTableOptions& options);

}  // namespace prt::experiments
