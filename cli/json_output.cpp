#include <chrono>
#include <cstdio>
#include <ctime>
#include <string>

#include "commands.h"
#include "prtlab/base/build_info.h"

namespace prt::cli {
namespace {
std::string g_command_line;
}

GlobalOptions& global_options() {
  static GlobalOptions opts;
  return opts;
}

void set_command_line(int argc, char** argv) {
  g_command_line.clear();
  for (int i = 0; i < argc; ++i) {
    if (i) g_command_line += ' ';
    g_command_line += argv[i];
  }
}

nlohmann::json provenance() {
  const auto& b = build_info();
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  char iso[32];
  std::strftime(iso, sizeof(iso), "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  return {{"version", b.version},
          {"git", b.git_hash},
          {"build", b.build_type},
          {"compiler", b.compiler},
          {"machine", machine_description()},
          {"time_utc", iso},
          {"command", g_command_line}};
}

void print_json(nlohmann::json j) {
  j["prtlab"] = provenance();
  std::printf("%s\n", j.dump(2).c_str());
}

}  // namespace prt::cli
