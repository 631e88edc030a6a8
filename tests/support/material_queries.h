#pragma once
// Material lookups for the tests that compare two shading paths (C++ against OpenCL, a backend
// against its reference): queries that reach every corner of the lookups, and the error
// measure those comparisons use.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "prtlab/compress/material_compressor.h"
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

/// The device's eval_lights against the C++ one over `queries` (each part's own light count `m`
/// values a query): the largest difference, relative to the peak of the query's C++ vector.
/// `where` receives the query, part and light of that largest difference.
inline double device_vs_cpp_eval_lights(ClContext& ctx,
                                        std::span<const CompressedMaterial* const> parts,
                                        std::span<const MaterialQuery> queries, TexelFilter filter,
                                        int m, std::string* where = nullptr) {
  const std::vector<const CompressedMaterial*> list(parts.begin(), parts.end());
  const std::vector<MaterialQuery> qs(queries.begin(), queries.end());
  const auto device = evaluate_materials_on_device(ctx, list, qs, filter);
  if (device.size() != qs.size() * static_cast<std::size_t>(m)) return INFINITY;
  std::vector<Rgb> cpp(static_cast<std::size_t>(m));
  double worst = 0;
  for (std::size_t i = 0; i < qs.size(); ++i) {
    list[static_cast<std::size_t>(qs[i].part)]->eval_lights(qs[i].uv, qs[i].view_local, cpp,
                                                            filter);
    float peak = 0;
    for (const Rgb& x : cpp) peak = std::max({peak, x.x, x.y, x.z});
    for (int j = 0; j < m; ++j)
      for (int c = 0; c < 3; ++c) {
        const double d = std::abs(device[i * m + j][c] - cpp[static_cast<std::size_t>(j)][c]) /
                         (peak > 0 ? peak : 1.0f);
        if (d > worst) {
          worst = d;
          if (where) *where = fmt::format("query {} part {} light {}", i, qs[i].part, j);
        }
      }
  }
  return worst;
}

/// The same over nearest and bilinear texel filtering; `where` names the filter too.
inline double device_vs_cpp_eval_lights(ClContext& ctx,
                                        std::span<const CompressedMaterial* const> parts,
                                        std::span<const MaterialQuery> queries, int m,
                                        std::string* where = nullptr) {
  double worst = 0;
  for (const auto filter : {TexelFilter::kNearest, TexelFilter::kBilinear}) {
    std::string at;
    const double d = device_vs_cpp_eval_lights(ctx, parts, queries, filter, m, &at);
    if (d >= worst) {
      worst = d;
      if (where) *where = at + (filter == TexelFilter::kNearest ? ", nearest" : ", bilinear");
    }
  }
  return worst;
}

}  // namespace prt::testing
