#pragma once
// Primary visibility by rasterisation: for every pixel centre, the nearest triangle the pixel's
// primary ray meets and where, computed from the mesh's projected triangles instead of a ray per
// pixel, so that its cost follows the triangles and the pixels they cover rather than the
// image (GBufferTracer's PrimaryRays::kRaster; docs/rendering.md "G-buffer").
//
// What it computes is what the ray tracer computes, to rounding: a pixel is covered by a
// triangle when its centre lies inside the triangle's projection (edge functions in double,
// each shared edge evaluated in one orientation for both of its triangles, so no centre falls
// between two neighbours); among the triangles covering it, the nearest along the ray wins, the
// lower index on an exact tie. Barycentrics are perspective-correct: those of the point where
// the ray meets the triangle's plane, which is what Embree returns as (u, v). Both faces count,
// as Embree counts both.
#include <cstdint>
#include <span>
#include <vector>

#include "prtlab/base/types.h"
#include "prtlab/geometry/camera.h"

namespace prt {

/// Per pixel (row-major, width x height): triangle index or -1, the barycentrics (b1, b2) of
/// its 2nd and 3rd vertex, and the distance from the eye along the unit ray.
struct PrimaryHits {
  std::vector<std::int32_t> triangle;
  std::vector<float> b1, b2, t;
  std::vector<double> view_depth;  ///< scratch: the depth test's view-axis depth
};

/// Rasterises the triangles for the camera into `hits` (resized; reused between calls). Returns
/// false, leaving `hits` unspecified, when a vertex lies at or behind the eye's plane (a
/// projection through the eye is unbounded): the caller then traces rays.
bool rasterize_primary(std::span<const Vec3> positions, std::span<const std::uint32_t> indices,
                       const Camera& camera, const CameraBasis& basis, PrimaryHits& hits);

}  // namespace prt
