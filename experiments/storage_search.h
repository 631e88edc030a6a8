#pragma once
// Equal storage (the central paper's Fig. 6): find the value of a backend's size knob at which
// its storage is within a tolerance of a target, spending as few compressions as possible.
//
// The knob's direction (size_knob.h) says which way storage moves; storage need only be
// monotone, not strictly (a stretch of values may store the same bytes). The search brackets
// the target between the knob's ends, then narrows the bracket by interpolating log(storage)
// linearly in the knob's own scale (log or linear), guarded so that every probe shrinks the
// bracket by at least a fifth (so it also terminates on steps and plateaus). An integer knob
// stops when no integer lies strictly inside the bracket. The answer is the probe closest to
// the target in ratio, with `reached` saying whether it is within the tolerance and `note` why
// not (the target lies outside the knob's range, or the storage jumps over it).
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "prtlab/compress/size_knob.h"

namespace prt::experiments {

struct KnobProbe {
  double value = 0;
  std::uint64_t bytes = 0;
};

struct StorageSearch {
  double value = 0;  ///< the chosen knob value (an integer for an int knob)
  std::uint64_t bytes = 0;
  double ratio = 0;  ///< bytes / target
  bool reached = false;
  std::string note;               ///< empty when reached
  std::vector<KnobProbe> probes;  ///< in the order they were made
};

/// `knob` resolved (min and max set); `integer` for a kInt parameter; `storage_at` compresses
/// at a value and returns the bytes. `max_probes` >= 2 bounds the calls.
StorageSearch search_equal_storage(const SizeKnob& knob, bool integer, std::uint64_t target,
                                   double tolerance, int max_probes,
                                   const std::function<std::uint64_t(double)>& storage_at);

/// The knob's values for a sweep: `count` values spread over [min, max] in its scale (log or
/// linear), rounded and de-duplicated for an int knob, ends included.
std::vector<double> knob_values(const SizeKnob& knob, bool integer, int count);

}  // namespace prt::experiments
