#pragma once
// Named, event-timed OpenCL commands (pattern 6 of STYLE.md, after pbrt-v4's GPU profiler).
// Every launch made through launch() (cl_launch.h) is recorded under its name; other commands
// (uploads, read-backs) can be recorded with record(). Times are device times from
// CL_PROFILING_COMMAND_START/END, so the queue must have profiling enabled (ClContext's has).
// Events are resolved lazily: record() does not wait, queries do.
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "prtlab/opencl/cl_include.h"

namespace prt {

/// Waits for `event` and returns its device execution time in milliseconds
/// (CL_PROFILING_COMMAND_END - START). Errors become ClError naming `device` and `what`.
double event_milliseconds(const cl::Event& event, std::string_view device, std::string_view what);

class KernelTimer {
 public:
  struct Stats {
    std::string name;
    std::uint64_t count = 0;  ///< commands recorded under this name
    double total_ms = 0.0;    ///< sum of device execution times
    double min_ms = 0.0;
    double max_ms = 0.0;
    double mean_ms() const { return count ? total_ms / static_cast<double>(count) : 0.0; }
  };

  /// Records one command. Cheap: the event is resolved when statistics are queried (or when
  /// many are pending, so memory stays bounded in long loops).
  void record(std::string_view name, const cl::Event& event);

  /// Waits for the pending events; statistics of every name, largest total time first.
  std::vector<Stats> stats();
  /// Statistics of one name (nullopt if never recorded).
  std::optional<Stats> stats(std::string_view name);
  /// Number of commands recorded under `name` (does not wait).
  std::uint64_t count(std::string_view name) const;

  /// A table: name, launches, total ms, mean us, min/max us, share of the total.
  /// Empty string when nothing was recorded.
  std::string summary(std::string_view title = "OpenCL kernel profile");

  void reset();

 private:
  void resolve_locked(bool wait_all);

  mutable std::mutex mutex_;
  std::vector<std::pair<std::string, cl::Event>> pending_;
  std::map<std::string, Stats, std::less<>> stats_;
  std::map<std::string, std::uint64_t, std::less<>> counts_;
};

}  // namespace prt
