#pragma once
// Changing a mesh's vertex count: decimation with meshoptimizer and subdivision for counts
// above the source's. Both keep UVs and part ids; normals and tangents are recomputed.
// Also welding, affine transforms and normalisation into the unit box.
#include <cstddef>
#include <cstdint>
#include <span>

#include "prtlab/geometry/mesh.h"

namespace prt {

/// Decimate to about target_vertices: meshopt_simplify (edge collapse, vertices keep their
/// positions and UVs) on a copy welded by position and UV, searching the target index count
/// until the surviving vertex count is within `tolerance` (relative) of the target, usually
/// exactly on it. Falls back to meshopt_simplifySloppy when edge collapse stops short (with a
/// warning). Vertices shared by triangles of different parts are split per part first, so
/// that every triangle keeps its part. Unused vertices are removed.
/// Throws ParameterError when the target is above the current count, below 4, or cannot be
/// reached within the tolerance.
Mesh decimate_to_vertex_count(const Mesh& mesh, std::size_t target_vertices,
                              double tolerance = 0.002);

/// One level of subdivision (each triangle into 4; new vertices at edge midpoints, shared
/// between neighbours; UVs interpolated linearly). With `smooth`, positions follow Loop's
/// rules (Loop 1987; boundary edges and vertices by the curve rule, boundary corners turning
/// by more than 30 degrees and non-manifold vertices stay fixed). Smoothing works on the
/// mesh welded by position, so UV seams do not open. For a closed mesh the vertex count
/// becomes V + E; the Euler characteristic is preserved.
Mesh subdivide(const Mesh& mesh, bool smooth = true);

/// Reach target_vertices: decimate when the mesh has more, otherwise subdivide until above
/// the target, then decimate. Returns the mesh unchanged (normals and tangents computed)
/// when it already has the target count.
Mesh resample_to_vertex_count(const Mesh& mesh, std::size_t target_vertices,
                              double tolerance = 0.002, bool smooth = true);

enum class WeldKey {
  kPositionAndUv,  ///< merge vertices with identical position and UV (UV seams stay split)
  kPosition,       ///< merge by position only; UVs are dropped (their seams would conflict)
};
/// Merge vertices at identical positions (and UVs); drops triangles that become degenerate
/// and removes unused vertices. Normals and tangents are recomputed when the mesh had them.
Mesh weld_vertices(const Mesh& mesh, WeldKey key = WeldKey::kPositionAndUv);

/// Apply an affine transform (scale, then rotation in degrees about x, then y, then z, then
/// translation): p' = Rz Ry Rx S p + t.
struct Transform {
  Vec3d scale{1.0};
  Vec3d rotate_deg{0.0};
  Vec3d translate{0.0};
  Mat3d linear() const;
};
/// Positions by the transform, normals by the inverse transpose of linear(), tangents by
/// linear() (then made orthogonal to the normal again). A mirroring transform (negative
/// determinant) also flips the winding, so that triangles stay counter-clockwise from the
/// front. Throws ParameterError for a singular transform (a zero scale).
void apply_transform(Mesh& mesh, const Transform& xf);
/// Scale and translate so the bounding box is centred at the origin with the largest extent 1
/// ... then lying on y = 0 when `on_ground`. Throws ParameterError for a mesh of zero extent.
void normalize_to_unit_box(Mesh& mesh, bool on_ground);
/// The same map, computed from `box` instead of the mesh's own bounds: pieces cut from one
/// model and normalised by the model's box keep their places relative to each other.
void normalize_to_unit_box(Mesh& mesh, bool on_ground, const Aabb& box);

/// The triangles whose part id is in `parts`, with the vertices they use (in their order) and
/// those vertices' UVs; the result is a single part (triangle_part empty). Normals and
/// tangents are dropped: a vertex on the cut would keep a normal smoothed over triangles it
/// no longer has.
Mesh select_parts(const Mesh& mesh, std::span<const std::uint16_t> parts);

/// Makes neighbouring triangles agree on their winding: within every component connected
/// over manifold edges (edges of exactly two triangles; vertices at one position count as
/// one), the triangles are flipped to the orientation that most of the component's area
/// already has, and a closed component is then turned to face outwards (positive enclosed
/// volume). Exported meshes often carry a few flipped faces, whose normals would cancel their
/// neighbours' in the smooth vertex normals. Returns the number of triangles flipped; normals
/// and tangents are recomputed when the mesh had them and anything changed.
std::size_t orient_consistently(Mesh& mesh);

}  // namespace prt
