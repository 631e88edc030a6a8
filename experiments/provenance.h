#pragma once
// Provenance of an experiment's results: what built the binary, where it ran, when, and how it
// was invoked. Every results file (markdown, CSV, JSON) carries it.
#include <nlohmann/json.hpp>
#include <string>

namespace prt {
class ClContext;
}

namespace prt::experiments {

struct Provenance {
  std::string version;
  std::string git_hash;    ///< short hash without the "-dirty" suffix
  bool git_dirty = false;  ///< the tree had uncommitted changes to tracked files at build time
  std::string build_type;
  std::string compiler;
  std::string hostname;
  std::string cpu_model;         ///< /proc/cpuinfo "model name"
  unsigned cores = 0;            ///< hardware threads
  double memory_gib = 0;         ///< /proc/meminfo MemTotal
  nlohmann::json opencl_device;  ///< DeviceInfo as JSON (docs/opencl.md), null without a device
  std::string date_utc;          ///< ISO 8601, when the experiment started
  std::string command_line;      ///< as typed (the CLI passes argv joined by spaces)

  /// One line for markdown: "git abc123 (dirty), Release, GCC 12, AMD EPYC ..., 2 cores, ...".
  std::string summary() const;
};

/// Collect the provenance now; `device` may be null (no OpenCL).
Provenance collect_provenance(const std::string& command_line, ClContext* device);

nlohmann::json to_json(const Provenance& p);

}  // namespace prt::experiments
