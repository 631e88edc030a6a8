#pragma once
// Automatic UVs for meshes that have none, so that a tiling BTF can be mapped onto every part
// (docs/rendering.md, "UV mapping"), and the stretch measure that reports their quality.
//
// Method: per-chart planar projection. Face normals are smoothed over edge neighbours (scan
// noise would shatter the charts); edges where the normals turn by more than 60 degrees are
// creases and never joined across. Charts are merged bottom-up (Garland, Willmott and Heckbert
// 2001, "Hierarchical face clustering"): every triangle starts alone, and the adjacent pair
// whose union has the smallest normal spread (plus small area and irregularity terms that keep
// charts even and compact) merges first, while every smoothed normal stays within
// `max_cone_deg` and every true normal within `hard_cone_deg` of the union's mean. Charts
// under `min_chart_area` then join the neighbour that fits them, and border triangles with two
// neighbours in another chart move there when they fit (straighter seams). Each chart is
// projected orthogonally onto the plane of its axis (area-weighted mean normal). Because every
// normal is within the hard cone, no projected triangle is flipped or degenerate and the
// stretch is bounded: a triangle at angle a from its axis keeps its length along one direction
// and shrinks by cos(a) across it (area ratio and anisotropy within 1 / cos(hard_cone_deg)).
//
// Orientation: on a chart with axis N, u runs along normalize(cross(+y, N)) and v along
// cross(N, u) (v points "up" on walls); on charts facing within 25 degrees of +-y u runs along
// +x projected into the plane instead. The UVs are right-handed (cross(n, dp/du) points along
// dp/dv), as the procedural shapes' are. Coordinates are absolute (positions relative to the
// mesh's bounding-box corner, divided by its largest extent), so neighbouring charts of similar
// axes nearly agree along their shared edge, and one UV unit is the mesh's largest extent
// (uv_scale = 4 tiles the BTF four times across the object).
//
// Seams: a vertex on the border between charts is duplicated, one copy per chart (same
// position, own UV); compute_smooth_normals smooths across these copies, so only the UVs and
// the tangents (which follow each chart's u) are discontinuous there. The BTF pattern shows a
// seam as a jump in its phase and, between charts of different orientation, in its direction.
#include <cstddef>
#include <span>

#include "prtlab/geometry/mesh.h"

namespace prt {

struct UvAtlasOptions {
  /// Half-angle of a chart's cone for the smoothed normals, in (0, 80].
  double max_cone_deg = 60;
  /// Half-angle for every triangle's own normal, in [max_cone_deg, 85]: bounds the stretch
  /// (area ratio >= cos) and keeps projected triangles from flipping.
  double hard_cone_deg = 75;
  /// Rounds of face-normal smoothing over edge neighbours before classification (-1: about
  /// sqrt(triangles) / 25, at least 1 and at most 16).
  int smoothing_rounds = -1;
  /// Charts under this fraction of the total area join the neighbour that fits them best
  /// (within the hard cone).
  double min_chart_area = 0.005;
};

struct UvAtlasReport {
  std::size_t charts = 0;
  std::size_t input_vertices = 0;
  std::size_t output_vertices = 0;  ///< input + seam copies (- vertices used by no triangle)
  double max_angle_deg = 0;         ///< largest angle between a triangle normal and its axis
};

/// A copy of `mesh` with generated UVs (existing UVs are replaced), its vertices split along
/// chart borders. Positions, normals (when present) and part ids are carried over; tangents
/// are dropped (compute_tangents derives them from the new UVs). Degenerate triangles (zero
/// area) join a neighbour's chart, or a chart of their own. ParameterError for bad options.
Mesh generate_uvs(const Mesh& mesh, const UvAtlasOptions& options = {},
                  UvAtlasReport* report = nullptr);

/// UV coordinates of `positions` under the orthogonal projection onto the plane of `axis`, with
/// the orientation and the units described above (`origin` = bounding-box corner, `extent` =
/// its largest side). An affine map of the positions; exposed for tests and tools.
Vec2 planar_uv(const Vec3& position, const Vec3d& axis, const Vec3d& origin, double extent);

/// Stretch of a mesh's UV mapping, per triangle, from the 2x2 Jacobian J of the map from the
/// triangle's plane to UV space (singular values s1 >= s2). The area ratio s1 s2 is normalised
/// by the whole mesh's (sum of UV areas / sum of 3D areas), so a uniform scale gives 1
/// everywhere. Statistics are area-weighted over the triangles with non-zero 3D area.
struct UvStretch {
  std::size_t triangles = 0;      ///< measured (non-degenerate in 3D)
  std::size_t flipped = 0;        ///< UV winding opposite to the 3D winding (det J < 0)
  std::size_t degenerate_uv = 0;  ///< zero UV area
  double area_ratio_min = 0, area_ratio_max = 0;  ///< normalised
  double area_ratio_p05 = 0, area_ratio_p95 = 0;  ///< area-weighted 5th and 95th percentiles
  double area_ratio_std = 0;                      ///< area-weighted standard deviation
  double anisotropy_max = 0;                      ///< max s1 / s2
  double anisotropy_mean = 0;                     ///< area-weighted mean of s1 / s2
};
/// Stretch over all triangles, or over the triangles of one part (`part` >= 0). The mesh must
/// have UVs (ParameterError otherwise).
UvStretch measure_uv_stretch(const Mesh& mesh, int part = -1);

}  // namespace prt
