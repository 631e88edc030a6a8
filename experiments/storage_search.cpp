#include "storage_search.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "prtlab/base/error.h"

namespace prt::experiments {
namespace {

double to_axis(const SizeKnob& k, double v) {
  return k.scale == SizeKnob::Scale::kLog ? std::log(v) : v;
}
double from_axis(const SizeKnob& k, double a) {
  return k.scale == SizeKnob::Scale::kLog ? std::exp(a) : a;
}

}  // namespace

std::vector<double> knob_values(const SizeKnob& knob, bool integer, int count) {
  if (!knob.min || !knob.max) throw ParameterError("knob_values: the size knob is not resolved");
  std::vector<double> out;
  const double a = to_axis(knob, *knob.min), b = to_axis(knob, *knob.max);
  for (int i = 0; i < count; ++i) {
    const double t = count == 1 ? 1.0 : static_cast<double>(i) / (count - 1);
    double v = from_axis(knob, a + t * (b - a));
    if (i == 0) v = *knob.min;
    if (i == count - 1) v = *knob.max;
    if (integer) v = std::round(v);
    if (out.empty() || v != out.back()) out.push_back(v);
  }
  return out;
}

StorageSearch search_equal_storage(const SizeKnob& knob, bool integer, std::uint64_t target,
                                   double tolerance, int max_probes,
                                   const std::function<std::uint64_t(double)>& storage_at) {
  if (!knob.min || !knob.max) throw ParameterError("equal storage: the size knob is not resolved");
  if (target == 0) throw ParameterError("equal storage: the target storage is 0 bytes");
  if (max_probes < 2) throw ParameterError("equal storage: max_probes must be >= 2");
  StorageSearch s;
  std::map<double, std::uint64_t> seen;
  const auto probe = [&](double v) {
    if (integer) v = std::round(v);
    if (auto it = seen.find(v); it != seen.end()) return it->second;
    const std::uint64_t bytes = storage_at(v);
    seen[v] = bytes;
    s.probes.push_back({v, bytes});
    return bytes;
  };
  const auto ratio = [&](std::uint64_t bytes) {
    return static_cast<double>(bytes) / static_cast<double>(target);
  };
  const auto within = [&](std::uint64_t bytes) {
    return std::abs(ratio(bytes) - 1.0) <= tolerance;
  };
  const auto finish = [&]() {
    // The closest probe in ratio (|log r|, so 0.9x and 1.11x count alike).
    const KnobProbe* best = nullptr;
    for (const auto& p : s.probes)
      if (!best || std::abs(std::log(ratio(p.bytes))) < std::abs(std::log(ratio(best->bytes))))
        best = &p;
    s.value = best->value;
    s.bytes = best->bytes;
    s.ratio = ratio(best->bytes);
    s.reached = within(best->bytes);
    return s;
  };

  // `small` is the end with the least storage, `large` the one with the most.
  const bool more = knob.direction == SizeKnob::Direction::kLargerIsMoreStorage;
  double small = more ? *knob.min : *knob.max, large = more ? *knob.max : *knob.min;
  const std::uint64_t b_small = probe(small);
  if (within(b_small)) return finish();
  const std::uint64_t b_large = probe(large);
  if (within(b_large)) return finish();
  if (target < b_small) {
    finish();
    s.note = fmt::format(
        "the target {:.3f} MB is below the least storage the knob '{}' reaches "
        "({:.3f} MB at {} = {})",
        target / 1e6, knob.key, b_small / 1e6, knob.key, small);
    return s;
  }
  if (target > b_large) {
    finish();
    s.note = fmt::format(
        "the target {:.3f} MB is above the most storage the knob '{}' reaches "
        "({:.3f} MB at {} = {})",
        target / 1e6, knob.key, b_large / 1e6, knob.key, large);
    return s;
  }
  double lo = to_axis(knob, small), hi = to_axis(knob, large);
  double log_lo = std::log(static_cast<double>(std::max<std::uint64_t>(b_small, 1)));
  double log_hi = std::log(static_cast<double>(std::max<std::uint64_t>(b_large, 1)));
  const double log_t = std::log(static_cast<double>(target));
  while (static_cast<int>(s.probes.size()) < max_probes) {
    // Interpolate, then keep the probe at least a fifth of the bracket from either end.
    double t = log_hi > log_lo ? (log_t - log_lo) / (log_hi - log_lo) : 0.5;
    t = std::clamp(t, 0.2, 0.8);
    double v = from_axis(knob, lo + t * (hi - lo));
    if (integer) {
      v = std::round(v);
      const double vlo = from_axis(knob, lo), vhi = from_axis(knob, hi);
      const double a = std::min(vlo, vhi), b = std::max(vlo, vhi);
      if (v <= a) v = a + 1;
      if (v >= b) v = b - 1;
      if (v <= a || v >= b) break;  // no integer strictly inside the bracket
    }
    const std::uint64_t bytes = probe(v);
    if (within(bytes)) return finish();
    if (bytes < target) {
      lo = to_axis(knob, v);
      log_lo = std::log(static_cast<double>(std::max<std::uint64_t>(bytes, 1)));
    } else {
      hi = to_axis(knob, v);
      log_hi = std::log(static_cast<double>(std::max<std::uint64_t>(bytes, 1)));
    }
  }
  finish();
  if (!s.reached)
    s.note = static_cast<int>(s.probes.size()) >= max_probes
                 ? fmt::format("not within {:.0f} % after {} compressions", 100 * tolerance,
                               s.probes.size())
                 : fmt::format(
                       "the storage jumps over the target between two neighbouring "
                       "values of '{}'",
                       knob.key);
  return s;
}

}  // namespace prt::experiments
