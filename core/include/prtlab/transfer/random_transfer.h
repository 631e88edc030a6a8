#pragma once
// Seeded random pixel-basis transfer matrices with the structure of a real T (at most one
// non-zero per column of a vertex block, counts in 1..s^2): the synthetic inputs of the
// conformance suite and the benchmarks' fallback when the data cache is missing.
#include <cstdint>
#include <vector>

#include "prtlab/transfer/transfer_matrix.h"

namespace prt {

struct RandomTransferSpec {
  std::size_t vertices = 16;
  int grid_side = 4;      ///< S (M = S^2)
  int resolution = 8;     ///< R (N = 6 R^2)
  int supersampling = 2;  ///< s: counts in 1..s^2
  double density = 0.5;   ///< probability that a (vertex, column) pair holds an entry
  std::vector<std::size_t> empty_vertices;  ///< vertices left without any entry
};

/// Every (vertex, column) pair is occupied with probability `density` by one entry in a uniformly
/// random local row with a uniformly random count. Deterministic for a seed (std::mt19937_64).
TransferMatrix random_transfer(std::uint64_t seed, const RandomTransferSpec& spec);

}  // namespace prt
