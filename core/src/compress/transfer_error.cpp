#include "prtlab/compress/transfer_error.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "prtlab/base/error.h"
#include "prtlab/base/relative_error.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/transfer/radiance_to_bins.h"

namespace prt {
namespace {

double frobenius_norm_sq(const TransferMatrix& t) {
  double s = 0;
  for (std::size_t i = 0; i < t.nnz(); ++i) {
    const double v = t.value(i);
    s += v * v;
  }
  return s;
}

// ||T~ z_c - T z_c||^2 per channel c for the light whose pixel radiance is `radiance`.
Vec3d residual_sq(const CompressedTransfer& ct, const TransferMatrix& t, const HemisphereGrid& grid,
                  const Cubemap& light) {
  LocalRadiance approx;
  ct.relight(ct.project_light(light), approx);
  const LocalRadiance pixel = to_pixel_basis(approx, grid);
  const std::vector<Vec3d> exact = relight_exact_double(t, light.light_vector());
  if (pixel.values.size() != exact.size())
    throw Error(fmt::format("backend '{}' relit {} values, the transfer has {} rows", ct.backend(),
                            pixel.values.size(), exact.size()));
  Vec3d s(0.0);
  for (std::size_t i = 0; i < exact.size(); ++i) {
    const Vec3d d = Vec3d(pixel.values[i]) - exact[i];
    s += d * d;
  }
  return s;
}

}  // namespace

FrobeniusError frobenius_error(const CompressedTransfer& ct, const TransferMatrix& t,
                               const HemisphereGrid& grid, int exact_relights,
                               int estimate_relights, std::uint64_t seed) {
  const int resolution = static_cast<int>(std::lround(std::sqrt(t.cols() / 6.0)));
  PRT_CHECK(static_cast<std::size_t>(6 * resolution * resolution) == t.cols(),
            "transfer with {} columns is no cubemap", t.cols());
  const double norm_sq = frobenius_norm_sq(t);
  const std::size_t n = t.cols();
  FrobeniusError out;
  double sum = 0;
  if (static_cast<std::size_t>(std::max(exact_relights, 0)) * 3 >= n) {
    // Unit lights, three columns per relight (one per channel).
    Cubemap light(resolution);
    for (std::size_t first = 0; first < n; first += 3) {
      std::fill(light.radiance.begin(), light.radiance.end(), Rgb(0.f));
      for (int c = 0; c < 3 && first + c < n; ++c) {
        const int k = static_cast<int>(first) + c;
        light.radiance[static_cast<std::size_t>(k)][c] =
            static_cast<float>(1.0 / light.layout.solid_angle(k));
      }
      const Vec3d r = residual_sq(ct, t, grid, light);
      sum += r.x + r.y + r.z;
      ++out.relights;
    }
    out.exact = true;
  } else {
    // Hutchinson: z_k = +-1 / solidAngle_k per pixel and channel, so that L = z.
    std::mt19937_64 rng(seed);
    std::bernoulli_distribution coin(0.5);
    Cubemap light(resolution);
    std::vector<double> samples;
    for (int r = 0; r < std::max(estimate_relights, 2); ++r) {
      for (int k = 0; k < static_cast<int>(n); ++k) {
        const float a = static_cast<float>(1.0 / light.layout.solid_angle(k));
        for (int c = 0; c < 3; ++c)
          light.radiance[static_cast<std::size_t>(k)][c] = coin(rng) ? a : -a;
      }
      const Vec3d s = residual_sq(ct, t, grid, light);
      samples.insert(samples.end(), {s.x, s.y, s.z});
      ++out.relights;
    }
    double mean = 0;
    for (double s : samples) mean += s;
    mean /= static_cast<double>(samples.size());
    double var = 0;
    for (double s : samples) var += (s - mean) * (s - mean);
    var /= static_cast<double>(samples.size() - 1);
    sum = mean;
    // Delta method: the standard error of sqrt(mean) is se(mean) / (2 sqrt(mean)).
    const double se_mean = std::sqrt(var / static_cast<double>(samples.size()));
    out.standard_error =
        norm_sq > 0 && mean > 0 ? se_mean / (2.0 * std::sqrt(mean * norm_sq)) : 0.0;
  }
  out.absolute = std::sqrt(std::max(sum, 0.0));
  out.relative = relative_to(out.absolute, std::sqrt(norm_sq),
                             "relative Frobenius error of a compressed transfer");
  return out;
}

VertexError max_vertex_error(const LocalRadiance& approx, const LocalRadiance& exact,
                             const HemisphereGrid& grid) {
  const LocalRadiance a = to_pixel_basis(approx, grid);
  if (a.values.size() != exact.values.size() || exact.dim != grid.cell_count())
    throw ParameterError("max_vertex_error: shapes differ");
  const auto m = static_cast<std::size_t>(exact.dim);
  std::vector<double> norm(exact.vertices, 0.0), diff(exact.vertices, 0.0);
  for (std::size_t p = 0; p < exact.vertices; ++p)
    for (std::size_t j = 0; j < m; ++j) {
      const Vec3d e(exact.values[p * m + j]), d = Vec3d(a.values[p * m + j]) - e;
      norm[p] += glm::dot(e, e);
      diff[p] += glm::dot(d, d);
    }
  double largest = 0;
  for (double v : norm) largest = std::max(largest, std::sqrt(v));
  const double floor = std::max(1e-6 * largest, 1e-300);
  VertexError out;
  for (std::size_t p = 0; p < exact.vertices; ++p) {
    const double rel = std::sqrt(diff[p]) / std::max(std::sqrt(norm[p]), floor);
    if (rel > out.max_relative) {
      out.max_relative = rel;
      out.worst_vertex = p;
    }
  }
  return out;
}

}  // namespace prt
