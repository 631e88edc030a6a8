#include "prtlab/opencl/cl_timer.h"

#include <fmt/format.h>

#include <algorithm>

#include "prtlab/opencl/cl_error.h"
#include "prtlab/base/log.h"

namespace prt {

double event_milliseconds(const cl::Event& event, std::string_view device, std::string_view what) {
  return cl_call(device, what, [&] {
    event.wait();
    const auto start = event.getProfilingInfo<CL_PROFILING_COMMAND_START>();
    const auto end = event.getProfilingInfo<CL_PROFILING_COMMAND_END>();
    return static_cast<double>(end - start) * 1e-6;
  });
}

namespace {

// Bounded memory in benchmark loops: past this many unresolved events, completed ones are
// folded in, and if none completed the oldest are waited for.
constexpr std::size_t kMaxPending = 4096;

bool is_complete(const cl::Event& e) {
  return e.getInfo<CL_EVENT_COMMAND_EXECUTION_STATUS>() <= CL_COMPLETE;  // error codes are < 0
}

}  // namespace

void KernelTimer::record(std::string_view name, const cl::Event& event) {
  std::lock_guard lock(mutex_);
  pending_.emplace_back(std::string(name), event);
  if (auto it = counts_.find(name); it != counts_.end()) {
    ++it->second;
  } else {
    counts_.emplace(std::string(name), 1);
  }
  if (pending_.size() >= kMaxPending) resolve_locked(false);
}

void KernelTimer::resolve_locked(bool wait_all) {
  std::vector<std::pair<std::string, cl::Event>> keep;
  for (std::size_t i = 0; i < pending_.size(); ++i) {
    auto& [name, event] = pending_[i];
    // An in-order queue completes in order, so waiting for the oldest half is enough to
    // make room.
    const bool must_wait = wait_all || i < pending_.size() / 2;
    if (!must_wait && !is_complete(event)) {
      keep.push_back(std::move(pending_[i]));
      continue;
    }
    auto it = stats_.find(name);
    if (it == stats_.end()) it = stats_.emplace(name, Stats{name}).first;
    Stats& s = it->second;
    ++s.count;
    try {
      event.wait();
      const double ms = static_cast<double>(event.getProfilingInfo<CL_PROFILING_COMMAND_END>() -
                                            event.getProfilingInfo<CL_PROFILING_COMMAND_START>()) *
                        1e-6;
      s.min_ms = s.count == 1 ? ms : std::min(s.min_ms, ms);
      s.max_ms = std::max(s.max_ms, ms);
      s.total_ms += ms;
    } catch (const cl::Error& e) {
      // A failed command or a queue without profiling: it still counts as a launch; the
      // failure itself is reported by whoever waits on the command.
      log_debug("KernelTimer: no profiling info for '{}' ({})", name, e.what());
    }
  }
  pending_ = std::move(keep);
}

std::vector<KernelTimer::Stats> KernelTimer::stats() {
  std::lock_guard lock(mutex_);
  resolve_locked(true);
  std::vector<Stats> out;
  for (const auto& [name, s] : stats_) out.push_back(s);
  std::stable_sort(out.begin(), out.end(),
                   [](const Stats& a, const Stats& b) { return a.total_ms > b.total_ms; });
  return out;
}

std::optional<KernelTimer::Stats> KernelTimer::stats(std::string_view name) {
  std::lock_guard lock(mutex_);
  resolve_locked(true);
  if (auto it = stats_.find(name); it != stats_.end()) return it->second;
  return std::nullopt;
}

std::uint64_t KernelTimer::count(std::string_view name) const {
  std::lock_guard lock(mutex_);
  auto it = counts_.find(name);
  return it == counts_.end() ? 0 : it->second;
}

std::string KernelTimer::summary(std::string_view title) {
  const std::vector<Stats> all = stats();
  if (all.empty()) return {};
  double total = 0.0;
  std::size_t width = 6;
  for (const auto& s : all) {
    total += s.total_ms;
    width = std::max(width, s.name.size());
  }
  std::string out =
      fmt::format("{}\n  {:<{}}  {:>9}  {:>11}  {:>10}  {:>10}  {:>10}  {:>6}\n", title, "kernel",
                  width, "launches", "total ms", "mean us", "min us", "max us", "%");
  for (const auto& s : all) {
    out += fmt::format("  {:<{}}  {:>9}  {:>11.3f}  {:>10.1f}  {:>10.1f}  {:>10.1f}  {:>6.1f}\n",
                       s.name, width, s.count, s.total_ms, s.mean_ms() * 1e3, s.min_ms * 1e3,
                       s.max_ms * 1e3, total > 0 ? 100.0 * s.total_ms / total : 0.0);
  }
  out += fmt::format("  {:<{}}  {:>9}  {:>11.3f}\n", "total", width, "", total);
  return out;
}

void KernelTimer::reset() {
  std::lock_guard lock(mutex_);
  resolve_locked(true);
  pending_.clear();
  stats_.clear();
  counts_.clear();
}

}  // namespace prt
