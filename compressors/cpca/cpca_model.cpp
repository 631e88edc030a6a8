// The stored model of backend `cpca` (stored_model.h): every row of T~ rebuilt in the pixel
// basis from its cluster's representatives and its weights as stored, then dotted with the
// light, in double (signal=brdf: then the K rows of each vertex through the stored Phi). The
// relight associates the other way (the light's dot with each representative first, then the
// per-row blend), so the two share no code.
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
  ModelRadiance rows;
  rows.values.assign(a_.rows(), Vec3d(0.0));
  rows.magnitude.assign(a_.rows(), Vec3d(0.0));
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
      rows.values[i] = value;
      rows.magnitude[i] = bound;
    }
  });
  if (a_.view_terms == 0) return rows;
  // The BRDF signal: the K rows of a vertex through Phi, |Phi| for the rounding bound.
  const auto m = static_cast<std::size_t>(a_.local_count);
  const auto k = static_cast<std::size_t>(a_.view_terms);
  ModelRadiance out;
  out.values.assign(a_.vertices * m, Vec3d(0.0));
  out.magnitude.assign(a_.vertices * m, Vec3d(0.0));
  for (std::size_t x = 0; x < a_.vertices; ++x)
    for (std::size_t o = 0; o < m; ++o)
      for (std::size_t i = 0; i < k; ++i) {
        const double phi = a_.view[o * k + i];
        out.values[x * m + o] += phi * rows.values[x * k + i];
        out.magnitude[x * m + o] += std::abs(phi) * rows.magnitude[x * k + i];
      }
  return out;
}

}  // namespace prt::cpca
