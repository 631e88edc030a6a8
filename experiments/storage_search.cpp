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
  const auto finish = [&](std::string note) {
    // A probe within the tolerance first, then the closest in |log r| (0.9x and 1.11x alike).
    const KnobProbe* best = nullptr;
    const auto better = [&](const KnobProbe& a, const KnobProbe& b) {
      if (within(a.bytes) != within(b.bytes)) return within(a.bytes);
      return std::abs(std::log(ratio(a.bytes))) < std::abs(std::log(ratio(b.bytes)));
    };
    for (const auto& p : s.probes)
      if (!best || better(p, *best)) best = &p;
    s.value = best->value;
    s.bytes = best->bytes;
    s.ratio = ratio(best->bytes);
    s.reached = within(best->bytes);
    s.note = s.reached ? std::string() : std::move(note);
    return s;
  };
  const auto pct = [&] { return fmt::format("{:g} %", 100 * tolerance); };

  // The bracket is kept in knob values (exact integers for an int knob); candidates are
  // interpolated on the knob's axis. `small` is the end with the least storage.
  const bool more = knob.direction == SizeKnob::Direction::kLargerIsMoreStorage;
  const double lo_end = integer ? std::ceil(*knob.min) : *knob.min;
  const double hi_end = integer ? std::floor(*knob.max) : *knob.max;
  double small = more ? lo_end : hi_end, large = more ? hi_end : lo_end;
  std::uint64_t b_small = probe(small);
  if (within(b_small)) return finish("");
  std::uint64_t b_large = probe(large);
  if (within(b_large)) return finish("");
  if (b_small > b_large)
    return finish(fmt::format(
        "the storage does not move the way the knob '{}' declares ({:.3f} MB at {} = {}, {:.3f} "
        "MB at {} = {})",
        knob.key, b_small / 1e6, knob.key, small, b_large / 1e6, knob.key, large));
  if (target < b_small)
    return finish(
        fmt::format("the target {:.3f} MB is below the least storage the knob '{}' "
                    "reaches ({:.3f} MB at {} = {})",
                    target / 1e6, knob.key, b_small / 1e6, knob.key, small));
  if (target > b_large)
    return finish(
        fmt::format("the target {:.3f} MB is above the most storage the knob '{}' "
                    "reaches ({:.3f} MB at {} = {})",
                    target / 1e6, knob.key, b_large / 1e6, knob.key, large));
  const double log_t = std::log(static_cast<double>(target));
  const auto log_of = [](std::uint64_t b) {
    return std::log(static_cast<double>(std::max<std::uint64_t>(b, 1)));
  };
  while (static_cast<int>(s.probes.size()) < max_probes) {
    // Interpolate log(storage), then keep the candidate at least a fifth of the bracket from
    // either end, so that every probe shrinks the bracket (plateaus and steps included).
    const double a = to_axis(knob, small), b = to_axis(knob, large);
    const double la = log_of(b_small), lb = log_of(b_large);
    const double t = std::clamp(lb > la ? (log_t - la) / (lb - la) : 0.5, 0.2, 0.8);
    double v = from_axis(knob, a + t * (b - a));
    const double lo = std::min(small, large), hi = std::max(small, large);
    if (integer) {
      v = std::round(v);
      if (v <= lo) v = lo + 1;
      if (v >= hi) v = hi - 1;
    }
    // Nothing strictly inside the bracket (an int knob at neighbouring values, or a real knob
    // narrowed to its last representable step) or a value already tried: the storage jumps over
    // the target.
    if (!(v > lo && v < hi) || seen.contains(v))
      return finish(
          fmt::format("the storage jumps over the target between {} = {} ({:.3f} MB) "
                      "and {} ({:.3f} MB)",
                      knob.key, small, b_small / 1e6, large, b_large / 1e6));
    const std::uint64_t bytes = probe(v);
    if (within(bytes)) return finish("");
    if (bytes < target) {
      small = v;
      b_small = bytes;
    } else {
      large = v;
      b_large = bytes;
    }
  }
  return finish(
      fmt::format("not within {} after {} compressions (closest: {:.3f} MB between {} "
                  "and {})",
                  pct(), s.probes.size(), b_small / 1e6, small, large));
}

}  // namespace prt::experiments
