#include "provenance.h"

#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <ctime>
#include <fstream>
#include <thread>

#include "prtlab/base/build_info.h"
#include "prtlab/opencl/cl_context.h"

namespace prt::experiments {
namespace {

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("model name", 0) != 0) continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos) break;
    const auto start = line.find_first_not_of(' ', colon + 1);
    return start == std::string::npos ? std::string("unknown CPU") : line.substr(start);
  }
  return "unknown CPU";
}

double memory_gib() {
  std::ifstream in("/proc/meminfo");
  for (std::string key; in >> key;) {
    if (key == "MemTotal:") {
      double kib = 0;
      in >> kib;
      return kib / (1024.0 * 1024.0);
    }
    in.ignore(1 << 10, '\n');
  }
  return 0.0;
}

std::string utc_now() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&now, &tm);
  char iso[32];
  std::strftime(iso, sizeof(iso), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return iso;
}

}  // namespace

Provenance collect_provenance(const std::string& command_line, ClContext* device) {
  const auto& b = build_info();
  Provenance p;
  p.version = b.version;
  p.git_hash = b.git_hash;
  constexpr std::string_view kDirty = "-dirty";
  if (p.git_hash.ends_with(kDirty)) {
    p.git_dirty = true;
    p.git_hash.resize(p.git_hash.size() - kDirty.size());
  }
  p.build_type = b.build_type;
  p.compiler = b.compiler;
  char host[256] = {};
  if (gethostname(host, sizeof(host) - 1) == 0) p.hostname = host;
  p.cpu_model = cpu_model();
  p.cores = std::thread::hardware_concurrency();
  p.memory_gib = memory_gib();
  p.opencl_device = device ? nlohmann::json(device->info()) : nlohmann::json(nullptr);
  p.date_utc = utc_now();
  p.command_line = command_line;
  return p;
}

std::string Provenance::summary() const {
  const std::string dev = opencl_device.is_object() && opencl_device.contains("label")
                              ? opencl_device["label"].get<std::string>()
                              : std::string("none");
  return fmt::format(
      "prtlab {} git {}{}, {} build ({}); {}, {} cores, {:.1f} GiB; OpenCL device: {}; {}", version,
      git_hash, git_dirty ? " (dirty)" : "", build_type, compiler, cpu_model, cores, memory_gib,
      dev, date_utc);
}

nlohmann::json to_json(const Provenance& p) {
  return {{"version", p.version},
          {"git", p.git_hash},
          {"git_dirty", p.git_dirty},
          {"build_type", p.build_type},
          {"compiler", p.compiler},
          {"machine",
           {{"hostname", p.hostname},
            {"cpu", p.cpu_model},
            {"cores", p.cores},
            {"memory_gib", p.memory_gib}}},
          {"opencl_device", p.opencl_device},
          {"date_utc", p.date_utc},
          {"command", p.command_line}};
}

}  // namespace prt::experiments
