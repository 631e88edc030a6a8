#pragma once
// Where prtlab finds its inputs and caches:
//   data (meshes, envmaps): $PRTLAB_DATA, else ~/.cache/prtlab/data  (scripts/setup.sh fills it)
//   stage cache:            $PRTLAB_CACHE, else ~/.cache/prtlab/cache
//   scenes:                 $PRTLAB_SCENES, else <source dir>/scenes
#include <filesystem>
#include <string>

namespace prt {

std::filesystem::path data_dir();
std::filesystem::path cache_dir();
std::filesystem::path scenes_dir();

/// Resolve a mesh reference: an existing path, else data_dir()/meshes/<name>. Throws an
/// InputError that points at scripts/setup.sh when a data file is missing.
std::filesystem::path resolve_mesh(const std::string& name);
/// Resolve an environment map: an existing path, else data_dir()/envmaps/<name>[.exr]
/// ("courtyard", "courtyard.exr").
std::filesystem::path resolve_envmap(const std::string& name);
/// Resolve a scene: an existing .toml path, else scenes_dir()/<name>.toml.
std::filesystem::path resolve_scene(const std::string& name);

}  // namespace prt
