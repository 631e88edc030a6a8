#pragma once
// A relative error ||a - b|| / ||b|| against a reference b that is zero is undefined: 0 / 0 is
// no perfect score, and x / 0 no size of an error. Every relative error prtlab reports (light
// fits, image diffs, relights, the harness's metrics) is divided here: against a zero reference
// it is NaN (JSON null, "undefined" in text) and the named warning "zero-reference" says what
// was compared and gives the absolute error instead.
#include <string_view>

namespace prt {

inline constexpr std::string_view kZeroReferenceWarning = "zero-reference";

/// error / reference when reference > 0; NaN and a "zero-reference" warning naming `what` and
/// the absolute error otherwise (a NaN reference stays NaN, without a warning).
double relative_to(double error, double reference, std::string_view what);

}  // namespace prt
