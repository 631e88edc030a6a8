#pragma once
// Material lookups for the tests that compare two shading paths (C++ against OpenCL, a backend
// against its reference): queries that reach every corner of the lookups, and the error
// measure those comparisons use.
#include <algorithm>
#include <cmath>
#include <random>
#include <span>
#include <vector>

#include "prtlab/render/device_material_eval.h"
#include "support/random_directions.h"

namespace prt::testing {

/// `count` seeded queries over `parts` parts: uv outside [0, 1) (wrap-around), views from the
/// zenith to below the horizon (every eighth one: clamped), then the tile centre seen from the
/// zenith and the origin seen at grazing incidence.
inline std::vector<MaterialQuery> material_queries(int parts, unsigned seed, int count = 48) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> uv(-1.5f, 2.5f);
  std::vector<MaterialQuery> out;
  for (int i = 0; i < count; ++i) {
    const Vec3d d = random_direction(rng);
    const Vec3 e(static_cast<float>(d.x), static_cast<float>(d.y),
                 static_cast<float>(i % 8 == 7 ? -std::abs(d.z) : std::abs(d.z)));
    out.push_back({i % parts, Vec2(uv(rng), uv(rng)), e});
  }
  out.push_back({0, Vec2(0.5f, 0.5f), Vec3(0.0f, 0.0f, 1.0f)});
  out.push_back({0, Vec2(0.0f, 0.0f), Vec3(1.0f, 0.0f, 0.0f)});
  return out;
}

/// Largest |a - b| over values and channels, relative to the largest |b| (absolute when b is 0).
inline double max_relative_rgb(std::span<const Rgb> a, std::span<const Rgb> b) {
  double err = 0, peak = 0;
  for (std::size_t i = 0; i < b.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      err = std::max(err, static_cast<double>(std::abs(a[i][c] - b[i][c])));
      peak = std::max(peak, static_cast<double>(std::abs(b[i][c])));
    }
  return peak > 0 ? err / peak : err;
}

}  // namespace prt::testing
