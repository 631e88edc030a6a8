#include "prtlab/transfer/local_radiance.h"

#include <algorithm>
#include <cmath>

#include "prtlab/base/error.h"
#include "prtlab/base/relative_error.h"

namespace prt {

std::string_view to_string(RadianceBasis b) {
  return b == RadianceBasis::kPixel ? "pixel" : "sh";
}

namespace {
void check_same_shape(const LocalRadiance& a, const LocalRadiance& b) {
  if (a.basis != b.basis || a.dim != b.dim || a.values.size() != b.values.size())
    throw Error(fmt::format("local radiance shapes differ: {} x {} ({}) vs {} x {} ({})",
                            a.vertices, a.dim, to_string(a.basis), b.vertices, b.dim,
                            to_string(b.basis)));
}
}  // namespace

double relative_l2_error(const LocalRadiance& a, const LocalRadiance& reference) {
  check_same_shape(a, reference);
  double num = 0, den = 0;
  for (std::size_t i = 0; i < a.values.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      const double d = static_cast<double>(a.values[i][c]) - reference.values[i][c];
      num += d * d;
      den += static_cast<double>(reference.values[i][c]) * reference.values[i][c];
    }
  return relative_to(std::sqrt(num), std::sqrt(den), "relative L2 error of a relight");
}

double relative_l1_error(const LocalRadiance& a, const LocalRadiance& reference) {
  check_same_shape(a, reference);
  double diff = 0, ref = 0;
  for (std::size_t i = 0; i < a.values.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      diff += std::abs(static_cast<double>(a.values[i][c]) - reference.values[i][c]);
      ref += std::abs(static_cast<double>(reference.values[i][c]));
    }
  return relative_to(diff, ref, "relative L1 error of a relight");
}

std::size_t count_nonfinite(std::span<const Rgb> values) {
  std::size_t n = 0;
  for (const Rgb& v : values)
    n += !(std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]));
  return n;
}

double max_relative_error(const LocalRadiance& a, const LocalRadiance& reference) {
  check_same_shape(a, reference);
  double peak = 0;
  for (const auto& v : reference.values)
    for (int c = 0; c < 3; ++c) peak = std::max(peak, std::abs(static_cast<double>(v[c])));
  const double floor = std::max(peak, 1e-30);
  double worst = 0;
  for (std::size_t i = 0; i < a.values.size(); ++i)
    for (int c = 0; c < 3; ++c)
      worst = std::max(
          worst, std::abs(static_cast<double>(a.values[i][c]) - reference.values[i][c]) / floor);
  return worst;
}

}  // namespace prt
