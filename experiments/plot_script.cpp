#include "plot_script.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <vector>

#include "prtlab/base/build_info.h"

namespace prt::experiments {
namespace fs = std::filesystem;

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::optional<std::string> python_with_matplotlib() {
  std::vector<std::string> candidates;
  if (const char* env = std::getenv("PRTLAB_PYTHON"); env && *env) candidates.emplace_back(env);
  candidates.emplace_back("/usr/bin/python3");
  candidates.emplace_back("python3");
  for (const auto& py : candidates) {
    const std::string probe = shell_quote(py) + " -c 'import matplotlib' >/dev/null 2>&1";
    if (std::system(probe.c_str()) == 0) return py;
  }
  return std::nullopt;
}

bool run_plot_script(const std::string& script, const std::string& args, bool quiet) {
  const auto path = fs::path(build_info().source_dir) / "scripts" / script;
  const auto py = python_with_matplotlib();
  if (!py || !fs::exists(path)) {
    std::fprintf(stderr,
                 "prtlab: no plot (needs python3 with matplotlib, package python3-matplotlib); "
                 "run: python3 scripts/%s %s\n",
                 script.c_str(), args.c_str());
    return false;
  }
  const std::string cmd = shell_quote(*py) + " " + shell_quote(path.string()) + " " + args +
                          (quiet ? " >/dev/null" : " >&2");
  if (std::system(cmd.c_str()) != 0) {
    std::fprintf(stderr, "prtlab: warning: the plot script failed: %s\n", cmd.c_str());
    return false;
  }
  return true;
}

}  // namespace prt::experiments
