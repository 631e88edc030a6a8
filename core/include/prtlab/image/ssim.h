#pragma once
// Structural similarity (SSIM, Wang, Bovik, Sheikh and Simoncelli 2004, "Image quality
// assessment: from error visibility to structural similarity") of an image against a reference,
// both in display values (tone-mapped, e.g. image_io.h's tone_mapped, nominally in [0, 1]).
//
// Per channel and pixel p, with Gaussian weights w_q = exp(-|q - p|^2 / (2 sigma^2)) over the
// (2 radius + 1)^2 window around p (the paper's 11 x 11, sigma 1.5), local means mu_x, mu_y,
// variances s_x^2, s_y^2 and covariance s_xy (all weighted, weights summing to 1):
//   SSIM(p) = (2 mu_x mu_y + C1) (2 s_xy + C2) / ((mu_x^2 + mu_y^2 + C1) (s_x^2 + s_y^2 + C2)),
//   C1 = (K1 L)^2, C2 = (K2 L)^2, K1 = 0.01, K2 = 0.03, L the data range (1 for display values).
// At the image border the window is cut to the pixels inside and its weights renormalised
// (scikit-image instead drops the border pixels; the paper does not say). The mean SSIM is the
// mean of SSIM(p) over the counted pixels (mask != 0; an empty mask counts every pixel) and the
// three channels; the windows themselves reach over uncounted pixels too (for a render, the
// background around the object's edge belongs to its structure). SSIM(x, x) = 1; it is symmetric
// in image and reference; 1 is the best and values can be negative.
#include <cstdint>
#include <span>
#include <vector>

#include "prtlab/image/image_io.h"

namespace prt {

struct SsimOptions {
  double sigma = 1.5;
  int radius = 5;  ///< window half-width (0: single pixels, SSIM of the values alone)
  double k1 = 0.01, k2 = 0.03;
  double data_range = 1.0;  ///< L
};

/// Per-pixel SSIM, the mean over the three channels, width * height values (row-major), for
/// every pixel whatever the mask. ParameterError when the sizes differ, the image is empty, or
/// the options are out of range (sigma <= 0, radius < 0, data_range <= 0).
std::vector<double> ssim_map(const RgbImage& image, const RgbImage& reference,
                             const SsimOptions& options = {});

/// Mean SSIM over the pixels where mask != 0 (empty mask: all); ParameterError as ssim_map and
/// when the mask has the wrong length or counts no pixel.
double ssim(const RgbImage& image, const RgbImage& reference,
            std::span<const std::uint8_t> mask = {}, const SsimOptions& options = {});

}  // namespace prt
