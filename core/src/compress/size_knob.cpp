#include "prtlab/compress/size_knob.h"

#include <algorithm>
#include <cmath>

#include "prtlab/base/error.h"

namespace prt {

std::string_view to_string(SizeKnob::Direction d) {
  switch (d) {
    case SizeKnob::Direction::kLargerIsMoreStorage:
      return "larger_is_more_storage";
    case SizeKnob::Direction::kLargerIsLessStorage:
      return "larger_is_less_storage";
  }
  return "?";
}

std::string_view to_string(SizeKnob::Scale s) {
  switch (s) {
    case SizeKnob::Scale::kLinear:
      return "linear";
    case SizeKnob::Scale::kLog:
      return "log";
  }
  return "?";
}

SizeKnob resolve_size_knob(const std::string& owner, const SizeKnob& knob,
                           std::span<const ParamSpec> params) {
  auto fail = [&](const std::string& why) {
    throw ParameterError(fmt::format("{}: size knob '{}': {}", owner, knob.key, why));
  };
  const auto spec = std::find_if(params.begin(), params.end(),
                                 [&](const ParamSpec& s) { return s.key == knob.key; });
  if (spec == params.end()) fail("not one of the backend's parameters");
  if (spec->type != ParamType::kInt && spec->type != ParamType::kReal)
    fail(fmt::format("a {} parameter; a size knob is int or real", to_string(spec->type)));

  SizeKnob out = knob;
  out.min = knob.min ? knob.min : spec->min;
  out.max = knob.max ? knob.max : spec->max;
  if (!out.min || !out.max)
    fail("the parameter has no bound on one side, so the knob must name its range");
  const double lo = *out.min, hi = *out.max;
  if (!std::isfinite(lo) || !std::isfinite(hi) || lo >= hi)
    fail(fmt::format("empty range [{}, {}]", lo, hi));
  if ((spec->min && lo < *spec->min) || (spec->max && hi > *spec->max))
    fail(fmt::format("range [{}, {}] leaves the parameter's [{}, {}]", lo, hi,
                     spec->min ? fmt::format("{}", *spec->min) : "-inf",
                     spec->max ? fmt::format("{}", *spec->max) : "inf"));
  if (spec->type == ParamType::kInt && (std::floor(lo) != lo || std::floor(hi) != hi))
    fail(fmt::format("range [{}, {}] of an int parameter has a fractional end", lo, hi));
  if (knob.scale == SizeKnob::Scale::kLog && lo <= 0)
    fail(fmt::format("log scale needs a positive minimum, not {}", lo));
  return out;
}

}  // namespace prt
