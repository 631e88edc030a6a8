// The stored model of backend `haar` (stored_model.h): every row's kept terms, decoded as the
// relight reads them, inverse-transformed to the pixel basis in double and dotted with the
// light. The relight transforms the light instead and sums in the wavelet domain, so the two
// meet only in the stored arrays (and in Parseval, which is what makes them agree).
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

#include "haar/haar.h"
#include "haar/haar_wavelet.h"
#include "prtlab/base/error.h"
#include "prtlab/numeric/float16.h"

namespace prt::haar {
namespace {

double stored_value(const HaarArrays& a, std::size_t row, std::uint32_t i) {
  switch (a.format) {
    case ValueFormat::kFloat32:
      return a.values32[i];
    case ValueFormat::kFloat16:
      return half_to_float(a.values16[i]);
    case ValueFormat::kS8:
      return static_cast<double>(a.codes[i]) * static_cast<double>(a.row_scales[row]);
  }
  return 0.0;
}

// Per coefficient k: |psi_k| |L| = (sum of |L| over its b x b support) / b, per channel, from
// prefix sums of each face.
std::vector<Vec3d> absolute_transform(const std::vector<Vec3d>& light, int r) {
  const auto face = static_cast<std::size_t>(r) * r;
  std::vector<Vec3d> out(light.size());
  std::vector<Vec3d> prefix(static_cast<std::size_t>(r + 1) * (r + 1));
  for (std::size_t f = 0; f < 6; ++f) {
    std::fill(prefix.begin(), prefix.end(), Vec3d(0.0));
    const auto at = [&](int x, int y) -> Vec3d& {
      return prefix[static_cast<std::size_t>(y) * (r + 1) + static_cast<std::size_t>(x)];
    };
    for (int y = 0; y < r; ++y)
      for (int x = 0; x < r; ++x)
        at(x + 1, y + 1) = glm::abs(light[f * face + static_cast<std::size_t>(y * r + x)]) +
                           at(x, y + 1) + at(x + 1, y) - at(x, y);
    for (int y = 0; y < r; ++y)
      for (int x = 0; x < r; ++x) {
        const HaarSupport s = haar_support(r, x, y);
        const Vec3d sum = at(s.x0 + s.size, s.y0 + s.size) - at(s.x0, s.y0 + s.size) -
                          at(s.x0 + s.size, s.y0) + at(s.x0, s.y0);
        out[f * face + static_cast<std::size_t>(y * r + x)] = sum / static_cast<double>(s.size);
      }
  }
  return out;
}

}  // namespace

ModelRadiance HaarTransfer::model_radiance(const Cubemap& radiance) const {
  const auto n = static_cast<std::size_t>(a_.pixel_count);
  if (radiance.layout.resolution() != a_.resolution)
    throw ParameterError(fmt::format("{}: a light of resolution {} for a transfer of R = {}", kName,
                                     radiance.layout.resolution(), a_.resolution));
  const auto omega = radiance.layout.solid_angles();
  std::vector<Vec3d> light(n);
  for (std::size_t k = 0; k < n; ++k) light[k] = Vec3d(radiance.radiance[k]) * omega[k];
  const std::vector<Vec3d> psi_l = absolute_transform(light, a_.resolution);
  ModelRadiance out;
  out.values.assign(a_.rows(), Vec3d(0.0));
  out.magnitude.assign(a_.rows(), Vec3d(0.0));
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, a_.rows(), 64), [&](const auto& r) {
    std::vector<double> row(n);
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      std::fill(row.begin(), row.end(), 0.0);
      Vec3d bound(0.0);
      for (std::uint32_t t = a_.offsets[i]; t < a_.offsets[i + 1]; ++t) {
        const std::uint32_t k = a_.wide ? a_.indices32[t] : a_.indices16[t];
        const double c = stored_value(a_, i, t);
        row[k] = c;
        bound += std::abs(c) * psi_l[k];
      }
      inverse_cubemap(row, a_.resolution);
      Vec3d value(0.0);
      for (std::size_t k = 0; k < n; ++k) value += row[k] * light[k];
      out.values[i] = value;
      out.magnitude[i] = bound;
    }
  });
  return out;
}

}  // namespace prt::haar
