#pragma once
// A material against the full BTF it represents, over every sample: all texels, view samples,
// light bins and colour channels, through CompressedMaterial::reflectance only (so any light
// basis is measured at the bins, in the full BTF's units). With b the full BTF's value and b~ the
// material's, d = b~ - b, per channel:
//
//   relative_l2      sqrt(sum d^2) / sqrt(sum b^2) over every sample. Dominated by the largest
//                    values (highlights), where a factorisation errs most in absolute terms.
//   average_relative Suykens et al. 2003's "average relative error" (section 4.4: "the average
//                    absolute and relative error ... The average relative error was large (up to
//                    100%), due to some very small values in the sampled ABRDF which blew up the
//                    relative errors"): the mean of |d| / |b| over the samples, unguarded, as the
//                    paper's words imply (its small values blow it up). The paper is silent on
//                    b = 0, where |d| / |b| is undefined: those samples are left out and counted
//                    (zero_samples). The paper does not say over what it averages before "up to":
//                    average_relative is the mean over every sample of every ABRDF (texel), and
//                    average_relative_worst_abrdf the largest mean of one ABRDF (its 3 channels).
//   average_relative_floored  the same with the denominator max(|b|, 0.01 m), m the largest
//                    |b| of that ABRDF and channel (prtlab's guard, not the paper's): values below
//                    1 % of the ABRDF's peak count with the error relative to that floor, so
//                    shadowed samples cannot dominate; b = 0 is then counted too.
//   average_abs      the mean |d| (the paper's "average absolute error").
//   cosine_l2        sum c_j d^2 and sum c_j b^2 instead of the plain sums, c_j = P_j / Omega_j
//                    the cell-mean cosine of light bin j (hemisphere_grid.h): grazing lights count
//                    less. b already carries c_j once (btf.h's units), so this counts the
//                    macro cosine a second time; it is the L2 error of the BRDF-like value b / c_j
//                    weighted by c_j^3.
//   white_light_l2   the error of what the material returns under a uniform white environment:
//                    per texel, view and channel the sums D = sum_j d and B = sum_j b over the
//                    light bins (the shading sum B(x, e) = sum_j b L*_j of btf.h with every
//                    L*_j = 1), then sqrt(sum D^2) / sqrt(sum B^2). This is the light-bin
//                    weighting of the rendering integral itself: every bin has the same solid
//                    angle and b holds the cosine, so each bin enters with weight 1 and errors
//                    of opposite sign within one view cancel as they do in a rendered pixel.
#include <cstdint>

#include "prtlab/btf/btf.h"
#include "prtlab/compress/material_compressor.h"

namespace prt {

/// The floor of average_relative_floored, as a fraction of the ABRDF channel's largest |b|.
inline constexpr double kRelativeErrorFloor = 0.01;

struct MaterialError {
  /// sqrt(sum (b~ - b)^2) / sqrt(sum b^2); NaN if b = 0 (base/relative_error.h)
  double relative_l2 = 0;
  double max_abs = 0;         ///< largest |b~ - b|
  double reference_l2 = 0;    ///< sqrt(sum b^2)
  std::uint64_t samples = 0;  ///< values compared (texels x views x lights x 3)
  /// Suykens 2003: mean |b~ - b| / |b| over the samples with b != 0 (NaN if there are none)
  double average_relative = 0;
  /// the largest mean |b~ - b| / |b| of one ABRDF (texel, all channels, b != 0)
  double average_relative_worst_abrdf = 0;
  /// mean |b~ - b| / max(|b|, kRelativeErrorFloor * max |b| of the ABRDF channel), all samples
  /// but those of an ABRDF channel that is zero everywhere (NaN if nothing is left)
  double average_relative_floored = 0;
  double average_abs = 0;          ///< mean |b~ - b|
  std::uint64_t zero_samples = 0;  ///< samples with b = 0, left out of average_relative
  double cosine_l2 = 0;            ///< relative L2 with light bin j weighted by c_j
  double white_light_l2 = 0;       ///< relative L2 of the light-bin sums (uniform white light)
};

/// ParameterError when the material's sampling differs from the BTF's. Sums in double,
/// parallel over texels with a fixed reduction order (the result does not depend on threads).
MaterialError material_error(const CompressedMaterial& material, const Btf& full);

}  // namespace prt
