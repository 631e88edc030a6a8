#pragma once
// The plugins a conformance suite runs on: PRTLAB_TEST_PLUGINS=/path/a.so:/path/b.so, loaded
// once per process before the suite enumerates the registries (prt::load_plugin). A plugin that
// fails to load is recorded, not fatal, so the suite can report it as a failing test.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "prtlab/compress/plugin.h"

namespace prt::testing {

struct PluginLoad {
  std::vector<std::string> paths;
  std::vector<std::string> names;   ///< what the plugins registered
  std::vector<std::string> errors;  ///< one message per plugin that failed to load
};

inline const PluginLoad& test_plugins() {
  static const PluginLoad load = [] {
    PluginLoad out;
    const char* list = std::getenv("PRTLAB_TEST_PLUGINS");
    std::string rest = list ? list : "";
    while (!rest.empty()) {
      const auto colon = rest.find(':');
      const std::string path = rest.substr(0, colon);
      rest = colon == std::string::npos ? "" : rest.substr(colon + 1);
      if (path.empty()) continue;
      out.paths.push_back(path);
      try {
        for (auto& n : load_plugin(path)) out.names.push_back(std::move(n));
      } catch (const std::exception& e) {
        out.errors.push_back(e.what());
        std::fprintf(stderr, "PRTLAB_TEST_PLUGINS: %s\n", e.what());
      }
    }
    return out;
  }();
  return load;
}

}  // namespace prt::testing
