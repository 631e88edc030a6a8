#pragma once
// Changing a mesh's vertex count: decimation with meshoptimizer and subdivision for counts
// above the source's. Both keep UVs and part ids; normals and tangents are recomputed.
#include <cstddef>

#include "prtlab/mesh.h"

namespace prt {

/// Decimate to about target_vertices (meshopt_simplify on a welded copy, searching the
/// target index count until the surviving vertex count is within `tolerance` relative).
/// Throws ParameterError when the target is above the current count.
Mesh decimate_to_vertex_count(const Mesh& mesh, std::size_t target_vertices, double tolerance = 0.002);

/// One level of subdivision (each triangle into 4; new vertices at edge midpoints, shared
/// between neighbours; Loop smoothing of positions when `smooth`).
Mesh subdivide(const Mesh& mesh, bool smooth = true);

/// Reach target_vertices by subdividing until above it, then decimating.
Mesh resample_to_vertex_count(const Mesh& mesh, std::size_t target_vertices, double tolerance = 0.002);

/// Merge vertices at identical positions (and UVs); removes unused vertices.
Mesh weld_vertices(const Mesh& mesh);

/// Apply an affine transform (scale, then rotation in degrees about x, y, z, then translation).
struct Transform {
  Vec3d scale{1.0};
  Vec3d rotate_deg{0.0};
  Vec3d translate{0.0};
  Mat3d linear() const;
};
void apply_transform(Mesh& mesh, const Transform& xf);
/// Scale and translate so the bounding box is centred at the origin with the largest extent 1
/// ... then lying on y = 0 when `on_ground`.
void normalize_to_unit_box(Mesh& mesh, bool on_ground);

}  // namespace prt
