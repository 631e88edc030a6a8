// The stored model of backend `cpca` (stored_model.h): every row of T~ rebuilt in the pixel
// basis from its cluster's representatives and its weights as stored, then dotted with the
// light, in double. The relight associates the other way (the light's dot with each
// representative first, then the per-row blend), so the two share no code.
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

#include "cpca/cpca.h"
#include "prtlab/base/error.h"

namespace prt::cpca {

ModelRadiance CpcaTransfer::model_radiance(const Cubemap& radiance) const {
  const auto n = static_cast<std::size_t>(a_.pixel_count);
  if (static_cast<std::size_t>(radiance.layout.pixel_count()) != n)
    throw ParameterError(fmt::format("{}: a light of N = {} for a transfer of N = {}", kName,
                                     radiance.layout.pixel_count(), n));
  const auto omega = radiance.layout.solid_angles();
  std::vector<Vec3d> light(n), magnitude(n);
  for (std::size_t k = 0; k < n; ++k) {
    light[k] = Vec3d(radiance.radiance[k]) * omega[k];
    magnitude[k] = glm::abs(light[k]);
  }
  ModelRadiance out;
  out.values.assign(a_.rows(), Vec3d(0.0));
  out.magnitude.assign(a_.rows(), Vec3d(0.0));
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, a_.rows(), 256), [&](const auto& r) {
    std::vector<double> row(n), size(n);
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const std::uint32_t c = a_.ids[i], f = a_.first[c], k = a_.first[c + 1] - f - 1;
      const double scale = a_.format == WeightFormat::kS8 ? a_.row_scales[i] : 1.0;
      const float* mean = a_.reps.data() + static_cast<std::size_t>(f) * n;
      for (std::size_t j = 0; j < n; ++j) {
        row[j] = mean[j];
        size[j] = std::abs(mean[j]);
      }
      const float* w = a_.weight_values.data() + a_.weight_offsets[i];
      for (std::uint32_t v = 0; v < k; ++v) {
        const double wv = scale * w[v];
        const float* rep = a_.reps.data() + static_cast<std::size_t>(f + 1 + v) * n;
        for (std::size_t j = 0; j < n; ++j) {
          row[j] += wv * rep[j];
          size[j] += std::abs(wv) * std::abs(rep[j]);
        }
      }
      Vec3d value(0.0), bound(0.0);
      for (std::size_t j = 0; j < n; ++j) {
        value += row[j] * light[j];
        bound += size[j] * magnitude[j];
      }
      out.values[i] = value;
      out.magnitude[i] = bound;
    }
  });
  return out;
}

}  // namespace prt::cpca
