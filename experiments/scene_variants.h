#pragma once
// Scene variants of a sweep: the same scene file with one or more of its grid settings
// (local_grid, cubemap_resolution, supersampling) changed, as the paper's Fig. 8 does.
//
// A variant is written as a scene file of its own (the base file's TOML with the settings
// replaced and the name suffixed), under <cache>/derived-scenes/, because every stage keys on
// the scene file's content: a variant gets its own transfer, compressions and points, and the
// same variant written twice is byte-identical, so it hits the cache.
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace prt::experiments {

struct SceneVariant {
  std::string base;                               ///< the scene as named in the experiment
  std::string name;                               ///< base, or "chair-local_grid16"
  std::filesystem::path file;                     ///< the (derived) scene file
  std::map<std::string, std::int64_t> overrides;  ///< empty for the base scene
};

/// Every combination of `grid` values for `scene` (a name or .toml path); just the scene
/// itself when `grid` is empty. Derived files go to `derived_dir`.
std::vector<SceneVariant> scene_variants(
    const std::string& scene, const std::map<std::string, std::vector<std::int64_t>>& grid,
    const std::filesystem::path& derived_dir);

}  // namespace prt::experiments
