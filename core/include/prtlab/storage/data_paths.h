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

/// Resolve a scene's mesh reference. An absolute path is used as it is; a relative path with a
/// folder ("meshes/a.obj", "./a.obj") is read from the scene file's folder; a bare name
/// ("bunny00.off") is data_dir()/meshes/<name> first, else the file next to the scene. The working
/// directory is never searched (it is when `scene_file` is empty: meshes built in code). Throws
/// an InputError naming the scene file and the places looked at.
std::filesystem::path resolve_mesh(const std::string& name,
                                   const std::filesystem::path& scene_file);
/// Resolve an environment map: an existing path, else data_dir()/envmaps/<name>[.exr]
/// ("courtyard", "courtyard.exr").
std::filesystem::path resolve_envmap(const std::string& name);
/// Resolve a scene: an existing .toml path, else scenes_dir()/<name>.toml.
std::filesystem::path resolve_scene(const std::string& name);

}  // namespace prt
