#pragma once
// What a frame does not need, for backend `bicluster` (docs/rendering.md, "Culling").
//
// Vertex subsets: a bicluster's rows are one local direction of many vertices, so a vertex
// subset cannot select whole biclusters. Phase 2 is per slice of 4 rows: a subset relights the
// slices holding one of its rows and writes only those rows (a slice's other lanes are summed
// but not stored). Phase 1 stays whole: which products the chosen slices read is only known by
// walking their ids, which costs about as much as phase 2 itself, against phase 1's few
// multiply-adds per bicluster.
//
// Dark cube faces: a bicluster whose columns all lie on faces the light leaves dark has
// P = sum t_m * 0 = +0 (the sum starts at +0, and +0 + -0 = +0), so phase 1 writes +0 without
// reading its columns: bit-identical.
#include <cstdint>
#include <span>
#include <vector>

#include "bicluster/bicluster.h"

namespace prt::bicluster {

/// Per bicluster (zero slots included), bit f set when one of its columns lies on cube face f
/// (0 for zero slots; every bit when N is not 6 R^2, so that nothing is skipped).
std::vector<std::uint8_t> bicluster_faces(const BiclusterArrays& a);

/// Per row of T, its place in phase 2: slice * kSliceRows + lane.
std::vector<std::uint32_t> row_lanes(const BiclusterArrays& a);

/// The slices holding the rows of a vertex subset, increasing, and per slice the lanes (bit c:
/// lane c) whose rows belong to the subset.
struct SliceSubset {
  std::vector<std::uint32_t> slices;
  std::vector<std::uint8_t> lanes;
};
/// `vertices` sorted, unique and < the vertex count; `lanes_of_rows` is row_lanes() of arrays
/// with `slices` slices and M = `local_count`.
SliceSubset slices_of(std::size_t slices, int local_count,
                      std::span<const std::uint32_t> lanes_of_rows,
                      std::span<const std::uint32_t> vertices);

}  // namespace prt::bicluster
