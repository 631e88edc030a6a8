#include "prtlab/compress/compressor.h"

#include <fmt/format.h>

#include "prtlab/base/error.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt {

void check_transfer_shape(const TransferInput& input, std::string_view backend) {
  const TransferMatrix& t = input.transfer;
  if (t.cols() != static_cast<std::size_t>(input.cubemap.pixel_count()) ||
      t.local_count() != input.grid.cell_count())
    throw ParameterError(fmt::format(
        "{}: the transfer is {} x {} per vertex but the bases give M = {}, N = {}", backend,
        t.local_count(), t.cols(), input.grid.cell_count(), input.cubemap.pixel_count()));
}

void check_pixel_light(const LightCoeffs& light, std::size_t pixels, std::string_view backend) {
  if (light.basis != "pixel" || light.values.size() != pixels)
    throw ParameterError(fmt::format(
        "{}: relight needs a pixel-basis light of N = {} values, got basis '{}' with {}", backend,
        pixels, light.basis, light.values.size()));
}

LightCoeffs pixel_light(const Cubemap& radiance, std::size_t pixels, std::string_view backend) {
  if (static_cast<std::size_t>(radiance.layout.pixel_count()) != pixels)
    throw ParameterError(
        fmt::format("{}: the light cubemap has N = {} pixels (R = {}), the transfer N = {}",
                    backend, radiance.layout.pixel_count(), radiance.layout.resolution(), pixels));
  return {"pixel", radiance.light_vector()};
}

void check_vertex_subset(std::span<const std::uint32_t> vertices, std::size_t vertex_count,
                         std::string_view backend) {
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    if (vertices[i] >= vertex_count)
      throw ParameterError(fmt::format("{}: vertex subset: vertex {} is not below the {} vertices",
                                       backend, vertices[i], vertex_count));
    if (i > 0 && vertices[i] <= vertices[i - 1])
      throw ParameterError(
          fmt::format("{}: vertex subset: vertices must be sorted and unique ({} follows {})",
                      backend, vertices[i], vertices[i - 1]));
  }
}

}  // namespace prt
