#include <fmt/format.h>
#include <unistd.h>

#include <fstream>
#include <string>
#include <thread>

#include "prtlab/base/build_info.h"

namespace prt {

std::string machine_description() {
  char host[256] = {};
  if (gethostname(host, sizeof(host) - 1) != 0) host[0] = '\0';
  std::string cpu = "unknown CPU";
  std::ifstream cpuinfo("/proc/cpuinfo");
  for (std::string line; std::getline(cpuinfo, line);) {
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) cpu = line.substr(line.find_first_not_of(' ', colon + 1));
      break;
    }
  }
  double mem_gib = 0.0;
  std::ifstream meminfo("/proc/meminfo");
  for (std::string key; meminfo >> key;) {
    if (key == "MemTotal:") {
      double kib = 0;
      meminfo >> kib;
      mem_gib = kib / (1024.0 * 1024.0);
      break;
    }
    meminfo.ignore(1 << 10, '\n');
  }
  return fmt::format("{}, {}, {} cores, {:.1f} GiB", host, cpu, std::thread::hardware_concurrency(),
                     mem_gib);
}

}  // namespace prt
