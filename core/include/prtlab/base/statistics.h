#pragma once
// Summary statistics of timing samples: every report (CLI, experiments, benches, tests) takes
// its medians here, so "median of K relights" means the same everywhere.
#include <algorithm>
#include <chrono>
#include <cstddef>
#include <span>
#include <vector>

namespace prt {

/// The median (mean of the two middle values for an even count); 0 for no samples.
inline double median(std::span<const double> samples) {
  if (samples.empty()) return 0.0;
  std::vector<double> v(samples.begin(), samples.end());
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
  const double upper = v[mid];
  if (v.size() % 2 == 1) return upper;
  return 0.5 * (upper + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid)));
}

/// Milliseconds since `t0` on the steady clock.
inline double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

/// Seconds since `t0` on the steady clock.
inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// Runs `f` `repeats` times (at least once) and returns the median wall-clock milliseconds.
template <typename F>
double median_ms_of(int repeats, F&& f) {
  std::vector<double> ms;
  for (int i = 0; i < std::max(1, repeats); ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    ms.push_back(ms_since(t0));
  }
  return median(ms);
}

}  // namespace prt
