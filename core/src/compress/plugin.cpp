#include "prtlab/compress/plugin.h"

#include <dlfcn.h>
#include <fmt/format.h>

#include <cstdio>
#include <cstdlib>
#include <mutex>

#include "prtlab/base/error.h"

namespace prt {
namespace {

/// What the library being opened has registered so far, and what went wrong.
struct PluginLoad {
  std::string path;
  std::vector<std::pair<std::string, std::function<void(const std::string&)>>> registered;
  std::vector<std::string> errors;
};

std::mutex g_load_mutex;
PluginLoad* g_loading = nullptr;  // non-null only inside load_plugin()'s dlopen

std::vector<std::filesystem::path>& loaded() {
  static std::vector<std::filesystem::path> paths;
  return paths;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += (s.empty() ? "" : "; ") + l;
  return s;
}

}  // namespace

namespace detail {

void register_static(const StaticRegistration& r) noexcept {
  const std::string origin = g_loading ? g_loading->path : std::string("built-in");
  std::string error;
  if (r.api != kPluginApiVersion) {
    error = fmt::format(
        "plugin API version {} does not match this prtlab's version {}; rebuild the plugin "
        "against this prtlab",
        r.api, kPluginApiVersion);
  } else {
    try {
      const std::string name = r.add(origin);
      if (g_loading) g_loading->registered.emplace_back(name, r.remove);
      return;
    } catch (const std::exception& e) {
      error = e.what();
    } catch (...) {
      error = fmt::format("unknown exception while registering a {}", r.kind);
    }
  }
  if (g_loading) {
    g_loading->errors.push_back(std::move(error));
    return;
  }
  std::fprintf(stderr, "prtlab: a built-in %.*s failed to register: %s\n",
               static_cast<int>(r.kind.size()), r.kind.data(), error.c_str());
  std::abort();
}

}  // namespace detail

std::vector<std::string> load_plugin(const std::filesystem::path& library) {
  if (!std::filesystem::exists(library)) throw InputError(library, "plugin library not found");
  const std::lock_guard lock(g_load_mutex);
  const auto canonical = std::filesystem::weakly_canonical(library);
  for (const auto& p : loaded())
    if (p == canonical) throw InputError(library, "this plugin is already loaded");

  PluginLoad load{library.string(), {}, {}};
  g_loading = &load;
  // The canonical (absolute) path, because dlopen() searches the library path, not the working
  // directory, for a name without a slash: `--plugin q8.so` must mean ./q8.so, as it does for
  // every other file argument.
  void* handle = ::dlopen(canonical.c_str(), RTLD_NOW | RTLD_LOCAL);
  g_loading = nullptr;
  if (!handle) throw InputError(library, fmt::format("cannot load plugin: {}", ::dlerror()));

  if (load.errors.empty() && load.registered.empty())
    load.errors.push_back(
        "not a prtlab plugin: it registered nothing (a plugin registers its backends with "
        "PRT_REGISTER_COMPRESSOR or PRT_REGISTER_MATERIAL, as built-in backends do)");
  if (!load.errors.empty()) {
    // Entries hold functions whose code lives in the library: drop them before closing it.
    for (auto& [name, remove] : load.registered) remove(name);
    load.registered.clear();
    ::dlclose(handle);
    throw InputError(library, joined(load.errors));
  }
  loaded().push_back(canonical);
  std::vector<std::string> names;
  for (const auto& [name, remove] : load.registered) names.push_back(name);
  return names;
}

std::vector<std::filesystem::path> loaded_plugins() {
  const std::lock_guard lock(g_load_mutex);
  return loaded();
}

}  // namespace prt
