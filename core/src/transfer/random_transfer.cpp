#include "prtlab/transfer/random_transfer.h"

#include <algorithm>
#include <random>
#include <utility>

namespace prt {

TransferMatrix random_transfer(std::uint64_t seed, const RandomTransferSpec& spec) {
  std::mt19937_64 rng(seed);
  const int m = spec.grid_side * spec.grid_side;
  const int n = 6 * spec.resolution * spec.resolution;
  const int max_count = spec.supersampling * spec.supersampling;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uniform_int_distribution<int> row_of(0, m - 1), count_of(1, max_count);
  std::vector<std::uint32_t> offsets{0}, columns;
  std::vector<std::uint8_t> counts;
  std::vector<std::vector<std::pair<std::uint32_t, std::uint8_t>>> rows(
      static_cast<std::size_t>(m));
  for (std::size_t v = 0; v < spec.vertices; ++v) {
    for (auto& r : rows) r.clear();
    const bool empty = std::find(spec.empty_vertices.begin(), spec.empty_vertices.end(), v) !=
                       spec.empty_vertices.end();
    for (int k = 0; k < n && !empty; ++k) {
      if (u(rng) >= spec.density) continue;
      const int row = row_of(rng);
      rows[static_cast<std::size_t>(row)].push_back(
          {static_cast<std::uint32_t>(k), static_cast<std::uint8_t>(count_of(rng))});
    }
    for (const auto& r : rows) {  // columns arrive in increasing order per row
      for (const auto& [c, x] : r) {
        columns.push_back(c);
        counts.push_back(x);
      }
      offsets.push_back(static_cast<std::uint32_t>(columns.size()));
    }
  }
  return TransferMatrix::from_csr(spec.vertices, m, n, spec.supersampling, std::move(offsets),
                                  columns, std::move(counts));
}

}  // namespace prt
