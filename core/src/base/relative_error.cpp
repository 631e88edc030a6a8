#include "prtlab/base/relative_error.h"

#include <cmath>
#include <limits>

#include "prtlab/base/named_warning.h"

namespace prt {

double relative_to(double error, double reference, std::string_view what) {
  if (reference > 0) return error / reference;
  if (reference == 0)
    log_warn_named(kZeroReferenceWarning,
                   "{}: the reference is zero, so the relative error is undefined (absolute "
                   "error {:.3g})",
                   what, error);
  return std::numeric_limits<double>::quiet_NaN();
}

}  // namespace prt
