#include "prtlab/storage/data_paths.h"

#include <cstdlib>

#include "prtlab/base/error.h"

namespace prt {
namespace fs = std::filesystem;
namespace {

fs::path home_cache() {
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return fs::path(xdg) / "prtlab";
  if (const char* home = std::getenv("HOME"); home && *home)
    return fs::path(home) / ".cache" / "prtlab";
  return fs::temp_directory_path() / "prtlab";
}

fs::path env_or(const char* var, const fs::path& fallback) {
  if (const char* v = std::getenv(var); v && *v) return fs::path(v);
  return fallback;
}

}  // namespace

fs::path data_dir() {
  return env_or("PRTLAB_DATA", home_cache() / "data");
}
fs::path cache_dir() {
  return env_or("PRTLAB_CACHE", home_cache() / "cache");
}
fs::path scenes_dir() {
  return env_or("PRTLAB_SCENES", fs::path(PRTLAB_SOURCE_DIR) / "scenes");
}

fs::path resolve_mesh(const std::string& name, const fs::path& scene_file) {
  const fs::path ref(name);
  const fs::path base = scene_file.empty() ? fs::path() : scene_file.parent_path();
  const fs::path& blame = scene_file.empty() ? ref : scene_file;
  std::error_code ec;
  if (ref.is_absolute()) {
    if (fs::is_regular_file(ref, ec)) return ref;
    throw InputError(blame, fmt::format("mesh '{}' not found", name));
  }
  if (ref.has_parent_path()) {
    const fs::path p = base / ref;
    if (fs::is_regular_file(p, ec)) return p;
    throw InputError(blame, fmt::format("mesh '{}' not found at {} (a relative mesh path is read "
                                        "from the scene file's folder)",
                                        name, p.string()));
  }
  // A bare name is a data-cache mesh first: a stray file of that name in the working directory
  // (or next to the scene) must not silently replace the mesh a paper's scene names.
  const fs::path cached = data_dir() / "meshes" / ref;
  if (fs::is_regular_file(cached, ec)) return cached;
  const fs::path local = base / ref;
  if (fs::is_regular_file(local, ec)) return local;
  throw InputError(
      blame, fmt::format("mesh '{}' not found: not in the data cache ({}){}; run "
                         "scripts/setup.sh --data, or set PRTLAB_DATA",
                         name, cached.string(),
                         scene_file.empty()
                             ? ""
                             : fmt::format(", nor next to the scene file ({})", local.string())));
}

fs::path resolve_envmap(const std::string& name) {
  if (fs::exists(name) && fs::is_regular_file(name)) return name;
  fs::path p = data_dir() / "envmaps" / name;
  if (!p.has_extension()) p += ".exr";
  if (fs::exists(p)) return p;
  throw InputError(p, fmt::format("environment map '{}' not found (not a path, and not one of "
                                  "city, courtyard, forest, interior, night, studio, sunrise, "
                                  "sunset in the data cache; run scripts/setup.sh --data)",
                                  name));
}

fs::path resolve_scene(const std::string& name) {
  if (fs::exists(name) && fs::is_regular_file(name)) return name;
  fs::path p = scenes_dir() / name;
  if (!p.has_extension()) p += ".toml";
  if (fs::exists(p)) return p;
  std::string known;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(scenes_dir(), ec))
    if (e.path().extension() == ".toml")
      known += (known.empty() ? "" : ", ") + e.path().stem().string();
  throw InputError(p, fmt::format("scene '{}' not found (known scenes: {})", name, known));
}

}  // namespace prt
