#pragma once
// The report of a result folder (experiment_run.h), drawn from its result.json alone, so it can
// be redrawn without recomputing: the plots (scripts/plot_experiment.py: run time and storage
// against error with each backend's Pareto front, the equal-storage figure of images and error
// maps, the scaling plot of scene variants, and SSIM where scikit-image is installed), then
// README.md: the tables, the papers' numbers beside ours, the winner at equal storage and by how
// much, and every file the folder holds.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace prt::experiments {

/// README.md of a result folder from its result.json (and perceptual.json when the plot script
/// wrote one).
std::string render_experiment_markdown(const nlohmann::json& result,
                                       const std::filesystem::path& folder);

/// Plots (unless `plots` is false) and README.md for `folder`. InputError when it holds no
/// result.json or an unreadable one.
void write_experiment_report(const std::filesystem::path& folder, bool plots, bool quiet);

}  // namespace prt::experiments
