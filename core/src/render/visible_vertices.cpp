#include "prtlab/render/visible_vertices.h"

#include <fmt/format.h>

#include "prtlab/base/error.h"

namespace prt {

std::vector<std::uint32_t> visible_vertices(const GBuffer& gbuffer, const Mesh& mesh) {
  const std::size_t triangles = mesh.indices.size() / 3;
  std::vector<std::uint8_t> seen(mesh.positions.size(), 0);
  for (const std::int32_t t : gbuffer.triangle) {
    if (t < 0) continue;
    if (static_cast<std::size_t>(t) >= triangles)
      throw ParameterError(fmt::format(
          "visible vertices: the G-buffer hits triangle {}, the mesh has {}", t, triangles));
    for (int c = 0; c < 3; ++c) seen[mesh.indices[3 * static_cast<std::size_t>(t) + c]] = 1;
  }
  std::vector<std::uint32_t> out;
  for (std::size_t v = 0; v < seen.size(); ++v)
    if (seen[v]) out.push_back(static_cast<std::uint32_t>(v));
  return out;
}

}  // namespace prt
