#pragma once
// The vertices a frame reads L* at (docs/rendering.md, "Culling"): shading a pixel interpolates
// L* between the three vertices of its hit triangle and reads nothing else, so the vertices of
// the hit triangles are exactly the rows of L* the frame needs; back-facing, occluded and
// off-screen vertices are never read.
#include <cstdint>
#include <vector>

#include "prtlab/geometry/mesh.h"
#include "prtlab/render/gbuffer.h"

namespace prt {

/// The vertices of the triangles hit in `gbuffer`, sorted and unique. Throws ParameterError when
/// a hit names a triangle the mesh does not have.
std::vector<std::uint32_t> visible_vertices(const GBuffer& gbuffer, const Mesh& mesh);

}  // namespace prt
