#pragma once
// Ng, Ramamoorthi, Hanrahan 2003's own approximation: the light, not T, is non-linearly
// approximated at run time. The light's Haar coefficients W L (haar_wavelet.h) are ranked by
// weight x |c| and only the best `terms` are kept; the relight is then the sparse product of
// the stored (quantised) wavelet T~ with that sparse light (compressors/haar/README.md, "The
// light's own approximation").
//
// The approximation is a parameter of the light projection (HaarTransfer::project_light with a
// LightApproximation): it never changes the compressed archive, so a run varies it without
// recompressing. Its result is a light in the wavelet basis, LightCoeffs{kLightBasis, W L with
// every dropped coefficient 0}, which both relight paths (C++ and OpenCL) accept beside the
// pixel light.
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "prtlab/base/types.h"
#include "prtlab/compress/compressor.h"
#include "prtlab/sphere/cubemap.h"

namespace prt::haar {

/// LightCoeffs::basis of a light given as its Haar coefficients (cubemap index order).
inline constexpr std::string_view kLightBasis = "haar";

/// How a light coefficient's magnitude is weighted when the terms are ranked. Ng 2003 calls its
/// selection "area-weighted"; on the sphere the area of a basis function's support can be read
/// two ways, and both are measured.
enum class LightWeight {
  kSolidAngle,  ///< the solid angle of the support (the sum of its pixels' exact solid angles)
  kFaceArea,    ///< the support's area on the cube face: b x b pixels, each pixel counting alike
  kNone,        ///< |c| alone: the L2-optimal approximation of the light itself
};
std::string_view to_string(LightWeight w);
/// "solid_angle", "face_area" or "none"; ParameterError naming the choices otherwise.
LightWeight light_weight_from(std::string_view name);

struct LightApproximation {
  std::size_t terms = 0;  ///< coefficients kept; 0 (or >= N): every one, the exact light
  LightWeight weight = LightWeight::kSolidAngle;
};

/// Per coefficient (the cubemap's index order) its weight under `w`. ParameterError unless the
/// resolution is a power of two.
std::vector<double> light_weights(const CubemapLayout& layout, LightWeight w);

/// The kept terms of a light, rising index.
struct SparseLight {
  std::vector<std::uint32_t> indices;
  std::vector<Rgb> values;
};

/// The `terms` coefficients of largest weight x |c| (|c| the Euclidean norm of the RGB
/// coefficient: one set of terms for the three channels, as the row kernel reads a float4 per
/// term), ties to the lower index; every non-zero one when terms is 0 or at least their count.
SparseLight truncate_light(std::span<const Rgb> coefficients, std::span<const double> weights,
                           std::size_t terms);

/// The dense wavelet-basis light of `sparse` (N values, 0 where a term was dropped).
LightCoeffs dense_light(const SparseLight& sparse, std::size_t pixels);
/// The non-zero terms of a wavelet-basis light (what truncate_light kept), rising index.
SparseLight sparse_terms(std::span<const Rgb> coefficients);

/// W L of a pixel light (transform_light), truncated under `approximation`, as a light in the
/// wavelet basis. With every term it holds exactly the coefficients relight_haar uses for the
/// pixel light, so the two relights have the same bits.
LightCoeffs approximate_light(std::span<const Rgb> pixel_light, const CubemapLayout& layout,
                              const LightApproximation& approximation);

}  // namespace prt::haar
