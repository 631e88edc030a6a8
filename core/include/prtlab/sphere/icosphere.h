#pragma once
// Near-uniform point sets on the unit sphere from a repeatedly subdivided icosahedron: the SRBF
// centres of Tsai and Shih 2006 (section 5.1: "repeatedly subdividing an icosahedron", 642
// vertices in their configuration). Level k has 10 * 4^k + 2 vertices: 12, 42, 162, 642, 2562,
// 10242 for k = 0 .. 5. Each subdivision splits every triangle into four at its edge midpoints,
// projected onto the sphere; the vertex order is deterministic (the 12 icosahedron vertices,
// then the midpoints in the order the edges are first met).
#include <span>
#include <vector>

#include "prtlab/base/types.h"

namespace prt {

inline constexpr int kMaxIcosphereLevel = 6;

/// Number of vertices at `level`: 10 * 4^level + 2.
int icosphere_vertex_count(int level);
/// The unit vertices of the icosahedron subdivided `level` times (0..kMaxIcosphereLevel;
/// ParameterError otherwise).
std::vector<Vec3d> icosphere_vertices(int level);
/// The level whose vertex count is `count` (12, 42, 162, ...), or ParameterError listing them.
int icosphere_level_for_count(int count);
/// The smallest geodesic distance (radians) between two of the points: O(n log n) is not
/// needed for the sizes used here; this is the all-pairs minimum. ParameterError for < 2 points.
double min_geodesic_distance(std::span<const Vec3d> points);

}  // namespace prt
