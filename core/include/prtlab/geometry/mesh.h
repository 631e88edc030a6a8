#pragma once
// Triangle mesh with per-vertex attributes. Positions, normals and UVs are float; the
// local frame per vertex (DESIGN.md "Local frame") is derived from normal and tangent.
//
// Conventions: triangles are counter-clockwise seen from the front (the side the normal
// points to); UV parametrisations of the procedural shapes are right-handed, so that
// cross(n, dp/du) points along dp/dv and LocalFrame's bitangent follows +v.
#include <cstdint>
#include <string>
#include <vector>

#include "prtlab/sphere/local_frame.h"
#include "prtlab/base/types.h"

namespace prt {

struct Aabb {
  Vec3 lo{0.f}, hi{0.f};
  Vec3 extent() const { return hi - lo; }
  Vec3 centre() const { return 0.5f * (lo + hi); }
};

struct Mesh {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;           ///< unit, per vertex (empty until computed)
  std::vector<Vec2> uvs;               ///< per vertex, empty when the mesh has none
  std::vector<Vec3> tangents;          ///< unit, orthogonal to the normal (empty until computed)
  std::vector<std::uint32_t> indices;  ///< 3 per triangle, counter-clockwise = front
  std::vector<std::uint16_t> triangle_part;  ///< part id per triangle (empty: all part 0)

  std::size_t vertex_count() const { return positions.size(); }
  std::size_t triangle_count() const { return indices.size() / 3; }
  bool has_uvs() const { return !uvs.empty(); }
  /// Part of triangle t (0 when triangle_part is empty).
  std::uint16_t part_of(std::size_t t) const {
    return triangle_part.empty() ? 0 : triangle_part[t];
  }
  /// Axis-aligned bounds of the positions ({0,0} for an empty mesh).
  Aabb bounds() const;
  /// Local frame of vertex v (requires normals; tangents where present).
  LocalFrame frame(std::size_t v) const;
  /// Appends other (indices offset, other's part ids shifted by `part`: its part p becomes
  /// part + p). An attribute present on one side only is completed: missing normals are
  /// computed, missing tangents computed from the normals (and UVs), missing UVs set to 0.
  void append(const Mesh& other, std::uint16_t part);
};

/// `input` itself when it has a normal and a tangent for every vertex; otherwise a copy with
/// the missing ones computed (compute_smooth_normals, compute_tangents), kept in `storage`.
/// The frames (Mesh::frame) of the result are the ones T, the G-buffer and the references use.
const Mesh& mesh_with_frames(const Mesh& input, Mesh& storage);

/// Angle-weighted smooth vertex normals (Thürmer and Wüthrich 1998). Vertices that share a
/// position but not an index (UV seams) are smoothed together when their own normals are
/// within 60 degrees of each other, so seams do not show while split hard edges (a box's
/// corners) stay sharp.
void compute_smooth_normals(Mesh& mesh);
/// Per-vertex tangents: from UVs where the mesh has them (Lengyel's method, Gram-Schmidt
/// against the normal), otherwise a stable frame from the normal alone. Computes normals
/// first when the mesh has none.
void compute_tangents(Mesh& mesh);

/// For every vertex, the lowest index of a vertex at exactly the same position (+0 and -0
/// equal). Vertices split at UV seams or hard edges share a representative.
std::vector<std::uint32_t> position_representatives(const Mesh& mesh);

}  // namespace prt
