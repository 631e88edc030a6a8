#include "prtlab/transfer/radiance_to_bins.h"

#include <fmt/format.h>

#include <cmath>
#include <map>
#include <mutex>
#include <numbers>

#include "prtlab/base/error.h"
#include "prtlab/sphere/spherical_harmonics.h"

namespace prt {

std::vector<double> sh_cell_integrals(const HemisphereGrid& grid, int order, int subdivisions) {
  if (order < 1 || order > kMaxShOrder)
    throw ParameterError(fmt::format("SH order {} is not in 1..{}", order, kMaxShOrder));
  if (subdivisions < 1) throw ParameterError("SH cell integrals: subdivisions must be >= 1");
  const int s = grid.side(), q = subdivisions, n = sh_count(order);
  const double weight = 2.0 * std::numbers::pi / (static_cast<double>(s) * s * q * q);
  std::vector<double> b(static_cast<std::size_t>(grid.cell_count()) * n, 0.0);
  std::vector<double> y(static_cast<std::size_t>(n));
  for (int row = 0; row < s; ++row)
    for (int col = 0; col < s; ++col) {
      double* out = &b[static_cast<std::size_t>(row * s + col) * n];
      for (int v = 0; v < q; ++v)
        for (int u = 0; u < q; ++u) {
          const Vec2d ab{(col + (u + 0.5) / q) / s, (row + (v + 0.5) / q) / s};
          sh_eval(order, glm::normalize(square_to_hemisphere(ab)), y);
          for (int i = 0; i < n; ++i) out[i] += weight * y[static_cast<std::size_t>(i)];
        }
    }
  return b;
}

namespace {

int order_of(int dim) {
  for (int order = 1; order <= kMaxShOrder; ++order)
    if (sh_count(order) == dim) return order;
  throw ParameterError(
      fmt::format("local radiance in the SH basis has {} values per vertex, which is no "
                  "order^2 with order <= {}",
                  dim, kMaxShOrder));
}

// B depends on (S, order) only; the frame loop converts on every light change.
const std::vector<double>& cached_integrals(const HemisphereGrid& grid, int order) {
  static std::mutex mutex;
  static std::map<std::pair<int, int>, std::vector<double>> cache;
  const std::lock_guard lock(mutex);
  auto [it, inserted] = cache.try_emplace({grid.side(), order});
  if (inserted) it->second = sh_cell_integrals(grid, order);
  return it->second;
}

}  // namespace

LocalRadiance to_pixel_basis(const LocalRadiance& radiance, const HemisphereGrid& grid) {
  const int m = grid.cell_count();
  if (radiance.values.size() != radiance.vertices * static_cast<std::size_t>(radiance.dim))
    throw ParameterError("local radiance: values do not match vertices x dim");
  if (radiance.basis == RadianceBasis::kPixel) {
    if (radiance.dim != m)
      throw ParameterError(fmt::format(
          "local radiance has {} pixel-basis values per vertex, the grid M = {}", radiance.dim, m));
    return radiance;
  }
  const int n = radiance.dim;
  const std::vector<double>& b = cached_integrals(grid, order_of(n));
  LocalRadiance out(RadianceBasis::kPixel, m, radiance.vertices);
  for (std::size_t p = 0; p < radiance.vertices; ++p) {
    const Rgb* c = &radiance.values[p * static_cast<std::size_t>(n)];
    Rgb* o = &out.values[p * static_cast<std::size_t>(m)];
    for (int j = 0; j < m; ++j) {
      Vec3d acc(0.0);
      const double* row = &b[static_cast<std::size_t>(j) * n];
      for (int i = 0; i < n; ++i) acc += row[i] * Vec3d(c[i]);
      o[j] = Rgb(acc);
    }
  }
  return out;
}

}  // namespace prt
