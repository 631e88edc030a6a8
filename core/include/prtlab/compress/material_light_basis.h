#pragma once
// The light side of a material: the basis its reflectance vectors b(u, e, .) are expressed in.
// Shading is B = sum_j b_j L*_j, so L* must be in the same basis with the same dimension.
//
//   pixel bins  M = S^2 values per vertex, one per cell of the local hemisphere grid (the full
//               BTF, and every material that keeps its light bins)
//   SH          order^2 coefficients per vertex in the local frame (a radiance transfer
//               texture: the light side projected onto spherical harmonics)
//
// A transfer backend relights into its output basis (CompressedTransfer::output_basis()); the
// frame loop asks shading_light_path() how L* reaches the material: directly when the bases
// agree, through the bins (to_pixel_basis, DeviceRadianceToBins) for an SH relight shaded with
// a pixel-bin material, and not at all for a pixel-basis relight shaded with an SH material
// (projecting L* onto SH is not implemented).
#include <string>
#include <string_view>

#include "prtlab/transfer/local_radiance.h"

namespace prt {

struct MaterialLightBasis {
  RadianceBasis basis = RadianceBasis::kPixel;
  int dim = 0;  ///< values per vertex: S^2 light bins, or order^2 SH coefficients

  static MaterialLightBasis pixel_bins(int light_side) {
    return {RadianceBasis::kPixel, light_side * light_side};
  }
  static MaterialLightBasis spherical_harmonics(int order) {
    return {RadianceBasis::kSphericalHarmonics, order * order};
  }
  bool operator==(const MaterialLightBasis&) const = default;
  /// "pixel bins (M = 64)", "SH (16 coefficients)": for messages and reports.
  std::string describe() const;
};

/// How the local radiance a transfer backend produces reaches a material's shading.
enum class LightPath {
  kDirect,       ///< the relight's output is in the material's basis
  kToPixelBins,  ///< an SH relight evaluated at the bins first (to_pixel_basis)
};

/// The path from a relight into `transfer_output` to a material of `material` basis.
/// ParameterError naming the backend and the material when there is none.
LightPath shading_light_path(RadianceBasis transfer_output, const MaterialLightBasis& material,
                             std::string_view backend, std::string_view material_backend);

/// ParameterError (prefixed by `who`) unless `radiance` is in `basis` with basis.dim values per
/// vertex and `vertices` vertices.
void check_light_basis(const MaterialLightBasis& basis, const LocalRadiance& radiance,
                       std::size_t vertices, std::string_view who);

}  // namespace prt
