#pragma once
// Triangle mesh with per-vertex attributes. Positions, normals and UVs are float; the
// local frame per vertex (DESIGN.md "Local frame") is derived from normal and tangent.
#include <cstdint>
#include <string>
#include <vector>

#include "prtlab/local_frame.h"
#include "prtlab/types.h"

namespace prt {

struct Aabb {
  Vec3 lo{0.f}, hi{0.f};
};

struct Mesh {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;              ///< unit, per vertex (empty until computed)
  std::vector<Vec2> uvs;                  ///< per vertex, empty when the mesh has none
  std::vector<Vec3> tangents;             ///< unit, orthogonal to the normal (empty until computed)
  std::vector<std::uint32_t> indices;     ///< 3 per triangle, counter-clockwise = front
  std::vector<std::uint16_t> triangle_part;  ///< part id per triangle (empty: all part 0)

  std::size_t vertex_count() const { return positions.size(); }
  std::size_t triangle_count() const { return indices.size() / 3; }
  bool has_uvs() const { return !uvs.empty(); }
  Aabb bounds() const;
  /// Local frame of vertex v (requires normals; tangents where present).
  LocalFrame frame(std::size_t v) const;
  /// Appends other (indices offset, part ids shifted to `part`).
  void append(const Mesh& other, std::uint16_t part);
};

/// Area-weighted smooth vertex normals (angle-weighted where that is more stable).
void compute_smooth_normals(Mesh& mesh);
/// Per-vertex tangents: from UVs where the mesh has them (Lengyel's method, Gram-Schmidt
/// against the normal), otherwise a stable frame from the normal alone.
void compute_tangents(Mesh& mesh);

}  // namespace prt
