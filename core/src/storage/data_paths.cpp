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

fs::path resolve_mesh(const std::string& name) {
  if (fs::exists(name)) return name;
  const fs::path p = data_dir() / "meshes" / name;
  if (fs::exists(p)) return p;
  throw InputError(p, fmt::format("mesh '{}' not found (not a path, and not in the data cache; "
                                  "run scripts/setup.sh --data, or set PRTLAB_DATA)",
                                  name));
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
