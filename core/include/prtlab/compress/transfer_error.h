#pragma once
// Measured error of a compressed transfer T~ against the exact T, through the public interface
// only (project_light + relight, results in any basis mapped to the bins by to_pixel_basis), so
// every backend, lossless or lossy, built in or a plugin, is measured the same way.
//
// Relative Frobenius error (the SE the CPCA and SRBF papers report, normalised):
//
//   ||T~ - T||_F / ||T||_F,   ||T~ - T||_F^2 = sum_k ||(T~ - T) e_k||^2.
//
// ||T||_F comes from T's CSR values. The numerator needs T~ column by column; each relight
// probes three columns (one per colour channel), so the exact value costs N / 3 relights
// (2,048 for N = 6,144). Above `exact_relights` the sum is estimated instead with Hutchinson's
// estimator: lights z with independent +-1 entries per pixel and channel give
// E ||(T~ - T) z||^2 = ||T~ - T||_F^2, three samples per relight, reported with its standard
// error. T is never densified.
//
// Per-vertex error: for each evaluation light, ||L~*_p - L*_p|| / ||L*_p|| over the vertex's M
// bins and three channels; the maximum over vertices and lights, vertices whose exact norm is
// below 1e-6 of the largest vertex norm counted in absolute terms against that floor.
#include <cstdint>
#include <span>

#include "prtlab/compress/compressor.h"
#include "prtlab/sphere/cubemap.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt {

struct FrobeniusError {
  double relative = 0;        ///< ||T~ - T||_F / ||T||_F (NaN for T = 0: undefined)
  double absolute = 0;        ///< ||T~ - T||_F (what is left to say when T = 0)
  double standard_error = 0;  ///< of `relative` (0 when exact)
  bool exact = false;         ///< all N columns probed
  int relights = 0;           ///< relights spent
};

/// `exact_relights`: the largest N / 3 computed exactly; `estimate_relights` otherwise
/// (seeded by `seed`).
FrobeniusError frobenius_error(const CompressedTransfer& ct, const TransferMatrix& t,
                               const HemisphereGrid& grid, int exact_relights = 2048,
                               int estimate_relights = 64, std::uint64_t seed = 1);

struct VertexError {
  double max_relative = 0;
  std::size_t worst_vertex = 0;
};
/// `approx` (any basis) against `exact` (pixel basis, same vertices and grid).
VertexError max_vertex_error(const LocalRadiance& approx, const LocalRadiance& exact,
                             const HemisphereGrid& grid);

}  // namespace prt
