#pragma once
// The images of an equal-storage result folder: every kept image as a PNG at its exact
// image's exposure, and false-colour maps of its per-pixel relative error on one colour scale
// for all backends (the largest 99th percentile among them), so that the maps compare.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <vector>

#include "point_measurement.h"
#include "scene_bench.h"

namespace prt::experiments {

/// Writes <folder>/images/<scene>-<env>-<view>-exact.png, ...-<backend>.png and
/// ...-<backend>-error.png, adds an "images" array to each outcome's record and returns the
/// exact images and error scales per (environment, view).
nlohmann::json write_scene_images(const SceneBench& bench,
                                  const std::vector<PointOutcome*>& outcomes,
                                  const std::filesystem::path& folder);

}  // namespace prt::experiments
