#pragma once
// A backend's size knob: the one parameter (besides `seed`) that trades storage against error,
// declared as data so that a harness can sweep every backend's rate-distortion curve without
// knowing any backend.
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "prtlab/compress/params.h"

namespace prt {

struct SizeKnob {
  /// Which way storage moves as the value grows (at fixed other parameters; not necessarily
  /// strictly: a backend may store the same bytes over a stretch of values).
  enum class Direction {
    kLargerIsMoreStorage,  ///< e.g. a kept fraction, an SH order, a cluster count
    kLargerIsLessStorage,  ///< e.g. an error budget
  };
  enum class Scale {
    kLinear,
    kLog,  ///< values spread by ratio (needs min > 0): error budgets, tolerances
  };

  std::string key;  ///< a kInt or kReal parameter of the backend (never a shared one)
  Direction direction = Direction::kLargerIsMoreStorage;
  /// The range worth sweeping, inside the parameter's own range. Unset: the parameter's bound;
  /// resolve_size_knob() fills both in.
  std::optional<double> min;
  std::optional<double> max;
  Scale scale = Scale::kLinear;
};

std::string_view to_string(SizeKnob::Direction d);  ///< "larger_is_more_storage" / "..._less_..."
std::string_view to_string(SizeKnob::Scale s);      ///< "linear" / "log"

/// Checks `knob` against the backend's parameter specs and returns it with min and max set.
/// A ParameterError naming `owner` when the key is not one of `params`, is not int or real,
/// has no bound on a side the knob leaves open, when the range leaves the parameter's range,
/// is empty (min >= max), has a non-integer end for an int, or is log-scaled with min <= 0.
SizeKnob resolve_size_knob(const std::string& owner, const SizeKnob& knob,
                           std::span<const ParamSpec> params);

}  // namespace prt
