#include "bicluster/bicluster_culling.h"

#include "prtlab/sphere/lit_faces.h"

namespace prt::bicluster {

std::vector<std::uint8_t> bicluster_faces(const BiclusterArrays& a) {
  const std::size_t n = static_cast<std::size_t>(a.pixel_count);
  std::vector<std::uint8_t> out(a.bicluster_count(), 0);
  const std::size_t per_face = n / kCubeFaces;
  for (std::size_t i = 0; i < out.size(); ++i) {
    for (std::uint32_t q = a.bic_col_offsets[i]; q < a.bic_col_offsets[i + 1]; ++q)
      out[i] |= static_cast<std::uint8_t>(
          n % kCubeFaces != 0 ? kAllFaces : 1u << (a.bic_columns[q] / per_face));
  }
  return out;
}

std::vector<std::uint32_t> row_lanes(const BiclusterArrays& a) {
  std::vector<std::uint32_t> out(a.rows(), 0);
  for (std::size_t p = 0; p < a.slice_rows.size(); ++p)
    if (a.slice_rows[p] < a.rows()) out[a.slice_rows[p]] = static_cast<std::uint32_t>(p);
  return out;
}

SliceSubset slices_of(std::size_t slices, int local_count,
                      std::span<const std::uint32_t> lanes_of_rows,
                      std::span<const std::uint32_t> vertices) {
  std::vector<std::uint8_t> lanes(slices, 0);
  const std::size_t m = static_cast<std::size_t>(local_count);
  for (const std::uint32_t v : vertices) {
    for (std::size_t j = 0; j < m; ++j) {
      const std::uint32_t p = lanes_of_rows[v * m + j];
      lanes[p / kSliceRows] |= static_cast<std::uint8_t>(1u << (p % kSliceRows));
    }
  }
  SliceSubset out;
  for (std::size_t s = 0; s < lanes.size(); ++s) {
    if (lanes[s] == 0) continue;
    out.slices.push_back(static_cast<std::uint32_t>(s));
    out.lanes.push_back(lanes[s]);
  }
  return out;
}

}  // namespace prt::bicluster
