#pragma once
// Plugins: shared libraries that register backends with the very macros a built-in backend uses
// (PRT_REGISTER_COMPRESSOR, PRT_REGISTER_MATERIAL). prtlab_core is a shared library, so a plugin
// linked against it (find_package(prtlab), target prtlab::core) registers into the same
// registries as the executable's built-in backends when load_plugin() opens it.
//
// Static registrars run while the library is opened, where nothing may throw. Every
// registration therefore goes through register_static(): it checks the plugin API version the
// registering code was compiled with before running any of that code, and keeps a failure for
// load_plugin() to report (which then removes everything the library registered and closes it).
// A failing built-in registration is a defect of the build: it prints the reason and aborts.
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace prt {

/// Bumped whenever a header a plugin compiles against changes in a way that breaks binaries.
inline constexpr int kPluginApiVersion = 7;

/// Opens a plugin library and returns the names it registered ("quantized8", ...). Throws
/// InputError naming the file when it is missing, cannot be opened, was built for another
/// plugin API version, registers nothing (not a prtlab plugin), registers a name that is
/// taken, or was loaded before; then nothing of it stays registered.
std::vector<std::string> load_plugin(const std::filesystem::path& library);

/// The plugins loaded so far in this process, in load order.
std::vector<std::filesystem::path> loaded_plugins();

namespace detail {

struct StaticRegistration {
  int api = 0;            ///< kPluginApiVersion the registering code was compiled with
  std::string_view kind;  ///< "compressor", "material": for messages
  std::function<std::string(const std::string& origin)> add;  ///< registers, returns the name
  std::function<void(const std::string& name)> remove;        ///< undoes add
};

/// Never throws (see above). `origin` passed to add is "built-in" or the plugin's path.
void register_static(const StaticRegistration& registration) noexcept;

}  // namespace detail
}  // namespace prt

// Unique names for the static registrars of PRT_REGISTER_COMPRESSOR and PRT_REGISTER_MATERIAL.
#define PRT_CONCAT_INNER(a, b) a##b
#define PRT_CONCAT(a, b) PRT_CONCAT_INNER(a, b)
