#include "prtlab/compress/material_light_basis.h"

#include <fmt/format.h>

#include "prtlab/base/error.h"

namespace prt {

std::string MaterialLightBasis::describe() const {
  if (basis == RadianceBasis::kPixel) return fmt::format("pixel bins (M = {})", dim);
  return fmt::format("{} ({} coefficients)", to_string(basis), dim);
}

LightPath shading_light_path(RadianceBasis transfer_output, const MaterialLightBasis& material,
                             std::string_view backend, std::string_view material_backend) {
  if (transfer_output == material.basis) return LightPath::kDirect;
  if (transfer_output == RadianceBasis::kSphericalHarmonics &&
      material.basis == RadianceBasis::kPixel)
    return LightPath::kToPixelBins;
  throw ParameterError(fmt::format(
      "backend '{}' relights into the {} basis, but material '{}' takes light in {}: there is "
      "no conversion of local radiance from the {} basis to it",
      backend, to_string(transfer_output), material_backend, material.describe(),
      to_string(transfer_output)));
}

void check_light_basis(const MaterialLightBasis& basis, const LocalRadiance& radiance,
                       std::size_t vertices, std::string_view who) {
  if (radiance.basis != basis.basis || radiance.dim != basis.dim)
    throw ParameterError(fmt::format(
        "{}: the material takes light in {}, the local radiance is in the {} basis with {} "
        "values per vertex",
        who, basis.describe(), to_string(radiance.basis), radiance.dim));
  if (radiance.vertices != vertices ||
      radiance.values.size() != radiance.vertices * static_cast<std::size_t>(radiance.dim))
    throw ParameterError(
        fmt::format("{}: local radiance has {} vertices x {} values, the mesh has {} vertices", who,
                    radiance.vertices, radiance.dim, vertices));
}

}  // namespace prt
