#pragma once
// The inputs of the conformance suite: small transfers every backend must handle, each with
// its bases and two non-negative test lights. Header-only because every tests/**/*_test.cpp
// is its own executable built from that one file.
//
//   random_*           TransferMatrix::from_csr on seeded random blocks: few distinct values
//                      (counts 1..s^2), at most one non-zero per column per vertex block, some
//                      empty rows; shapes vary M, N, s, the density and the column width
//                      (random_wide: N = 98,304 > 65,536 columns, stored as u32)
//   sphere_over_plane  a real transfer: make_sphere over make_plane through compute_transfer
//                      (R = 8, S = 4, s = 2), with shadows and fractional counts
//   all_zero           vertices whose blocks hold no non-zero at all (nnz = 0)
//
// A backend whose entry asks for an SH transfer (BackendInputs::sh_order) gets one of that
// order with every case (CaseData::input(entry)): sphere_over_plane the real one of
// compute_transfer; the others, which have no geometry, the SH transfer of T's own operator
// (sh_transfer_of_pixels below), so that an all-zero T has all-zero SH matrices too.
//
// Each case's description names its seed, so a failure message says how to reproduce it.
#include <fmt/format.h>

#include <algorithm>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "prtlab/compress/compressor.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/geometry/procedural_shapes.h"
#include "prtlab/sphere/cubemap.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/sphere/spherical_harmonics.h"
#include "prtlab/transfer/radiance_to_bins.h"
#include "prtlab/transfer/random_transfer.h"
#include "prtlab/transfer/sh_transfer.h"
#include "prtlab/transfer/transfer_matrix.h"
#include "support/sphere_over_plane.h"

namespace prt::conformance {

struct CaseData {
  std::string name;
  std::string description;  ///< shape and seed
  TransferMatrix transfer;
  CubemapLayout cubemap;
  HemisphereGrid grid;
  std::vector<Cubemap> lights;  ///< non-negative radiance at resolution R
  /// Builds the case's SH transfer of an order (same vertices as T).
  std::function<ShTransfer(const CaseData&, int order)> make_sh;

  /// T and the bases only.
  TransferInput input() const { return TransferInput{transfer, nullptr, cubemap, grid}; }
  /// What `entry` declares it reads: T, and the SH transfer when it asks for one.
  TransferInput input(const CompressorEntry& entry) const {
    TransferInput in = input();
    if (entry.inputs.sh_order > 0) in.sh = &sh(entry.inputs.sh_order);
    return in;
  }
  /// The SH transfer of `order`, built on first use.
  const ShTransfer& sh(int order) const {
    const std::lock_guard lock(sh_mutex);
    auto& slot = sh_built[order];
    if (!slot) slot = std::make_unique<ShTransfer>(make_sh(*this, order));
    return *slot;
  }

  // The cache of sh(); public only so that CaseData stays an aggregate.
  mutable std::mutex sh_mutex;
  mutable std::map<int, std::unique_ptr<ShTransfer>> sh_built;
};

/// The SH transfer of a pixel-basis T, for cases without geometry: the light's SH expansion
/// sampled at the pixel centres (times their solid angles) is what T transfers, and cell j's
/// L*_j spread evenly over the cell is projected onto the local SH, so
///   M_p[i][k] = sum_(j, pixel q) (B[j, i] / cell solid angle) T_p[j, q] y_k(d_q) dOmega_q
/// with B the cell integrals of radiance_to_bins.h. M_p l reproduces T L for lights that are
/// band-limited to the order, up to the sampling at pixel centres and the SH truncation of
/// each vertex's cell values.
inline ShTransfer sh_transfer_of_pixels(const TransferMatrix& t, const CubemapLayout& cubemap,
                                        const HemisphereGrid& grid, int order) {
  const int n = sh_count(order), m = t.local_count();
  const std::vector<double> b = sh_cell_integrals(grid, order);
  const double cell = grid.cell_solid_angle();
  ShTransfer sh(order, t.vertex_count());
  std::vector<double> y(static_cast<std::size_t>(n));
  for (std::size_t v = 0; v < t.vertex_count(); ++v) {
    const std::span<double> out = sh.mutable_matrix(v);
    for (int j = 0; j < m; ++j) {
      const std::size_t row = v * static_cast<std::size_t>(m) + static_cast<std::size_t>(j);
      for (std::uint32_t e = t.row_offsets()[row]; e < t.row_offsets()[row + 1]; ++e) {
        const int q = static_cast<int>(t.column(e));
        sh_eval(order, cubemap.direction(q), y);
        const double w = t.value(e) * cubemap.solid_angle(q) / cell;
        for (int i = 0; i < n; ++i) {
          const double bi = b[static_cast<std::size_t>(j) * n + i] * w;
          for (int k = 0; k < n; ++k) out[static_cast<std::size_t>(i) * n + k] += bi * y[k];
        }
      }
    }
  }
  return sh;
}

/// A random pixel-basis transfer: every (vertex, column) pair is occupied with probability
/// `density` by one entry in a random local row with a random count in 1..s^2. Vertices listed
/// in `empty_vertices` get no entry.
inline TransferMatrix random_transfer(std::uint64_t seed, std::size_t vertices, int grid_side,
                                      int resolution, int supersampling, double density,
                                      const std::vector<std::size_t>& empty_vertices = {}) {
  return prt::random_transfer(seed, RandomTransferSpec{vertices, grid_side, resolution,
                                                       supersampling, density, empty_vertices});
}

/// Two lights: uniform random radiance in [0, 1) per channel, and a high-dynamic-range one
/// (dim sky plus three bright pixels, up to 500).
inline std::vector<Cubemap> test_lights(int resolution, std::uint64_t seed) {
  std::mt19937_64 rng(seed ^ 0x9e3779b97f4a7c15ull);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  Cubemap random(resolution), hdr(resolution);
  for (auto& r : random.radiance) r = Rgb(u(rng), u(rng), u(rng));
  for (auto& r : hdr.radiance) r = Rgb(0.05f + 0.01f * u(rng), 0.06f, 0.08f);
  std::uniform_int_distribution<std::size_t> pixel(0, hdr.radiance.size() - 1);
  for (float peak : {500.0f, 120.0f, 35.0f})
    hdr.radiance[pixel(rng)] = Rgb(peak, 0.9f * peak, 0.7f * peak);
  return {std::move(random), std::move(hdr)};
}

using prt::testing::sphere_over_plane_transfer;

struct CaseSpec {
  std::string name;
  std::function<std::unique_ptr<CaseData>()> make;
};

inline std::unique_ptr<CaseData> make_case(std::string name, std::string description,
                                           TransferMatrix t, int resolution, int grid_side,
                                           std::uint64_t light_seed) {
  auto c = std::unique_ptr<CaseData>(new CaseData{std::move(name),
                                                  std::move(description),
                                                  std::move(t),
                                                  CubemapLayout(resolution),
                                                  HemisphereGrid(grid_side),
                                                  {},
                                                  {},
                                                  {},
                                                  {}});
  c->lights = test_lights(resolution, light_seed);
  c->make_sh = [](const CaseData& d, int order) {
    return sh_transfer_of_pixels(d.transfer, d.cubemap, d.grid, order);
  };
  return c;
}

/// A random case: seed, vertices, S (M = S^2), R (N = 6 R^2), s, density, empty vertices.
inline CaseSpec random_case(std::string name, std::uint64_t seed, std::size_t vertices,
                            int grid_side, int resolution, int supersampling, double density,
                            std::vector<std::size_t> empty = {}) {
  return {
      name, [=] {
        const std::string description = fmt::format(
            "{}: random_transfer(seed = {}, vertices = {}, S = {}, R = {}, s = {}, density = {})",
            name, seed, vertices, grid_side, resolution, supersampling, density);
        return make_case(
            name, description,
            random_transfer(seed, vertices, grid_side, resolution, supersampling, density, empty),
            resolution, grid_side, seed);
      }};
}

/// Every case, in a fixed order (test names are derived from it).
inline const std::vector<CaseSpec>& case_specs() {
  static const std::vector<CaseSpec> specs = {
      random_case("random_small", 11, 6, 2, 2, 2, 0.6),
      random_case("random_unit_counts", 23, 9, 3, 2, 1, 0.35),
      random_case("random_dense_s3", 37, 4, 4, 4, 3, 0.95, {2}),
      random_case("random_long_rows", 41, 3, 1, 4, 2, 0.8),
      random_case("random_wide", 53, 3, 2, 128, 2, 0.003),
      {"sphere_over_plane",
       [] {
         auto c = make_case("sphere_over_plane",
                            "sphere_over_plane: make_sphere(0.5, 12, 6) at (0.2, 0.8, -0.1) over "
                            "make_plane(3, 3, 4), "
                            "R = 8, S = 4, s = 2, light seed 61",
                            sphere_over_plane_transfer().transfer, 8, 4, 61);
         c->make_sh = [](const CaseData&, int order) {
           return *sphere_over_plane_transfer(order).sh;
         };
         return c;
       }},
      {"all_zero",
       [] {
         return make_case("all_zero",
                          "all_zero: 5 vertices, S = 2, R = 2, s = 2, nnz = 0, light seed 71",
                          random_transfer(71, 5, 2, 2, 2, 0.0), 2, 2, 71);
       }},
  };
  return specs;
}

/// The case of that name, built once per process.
inline const CaseData& case_data(const std::string& name) {
  static std::mutex mutex;
  static std::map<std::string, std::unique_ptr<CaseData>> built;
  const std::lock_guard lock(mutex);
  auto it = built.find(name);
  if (it != built.end()) return *it->second;
  for (const auto& spec : case_specs())
    if (spec.name == name) return *(built[name] = spec.make());
  throw std::out_of_range("no conformance case named " + name);
}

}  // namespace prt::conformance
