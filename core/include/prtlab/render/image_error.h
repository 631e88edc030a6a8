#pragma once
// Error of a rendered image against a reference image (docs/image-error.md): scalar metrics and
// a false-colour picture of the per-pixel relative error.
//
// Metrics over the counted pixels P (a mask selects them, e.g. the G-buffer's hits; an empty
// mask counts every pixel), with a and b the image and the reference, summed over P and the
// three channels:
//   relative_l2 = sqrt(sum (a - b)^2) / sqrt(sum b^2)
//   rmse        = sqrt(sum (a - b)^2 / (3 |P|))
//   max_abs     = max |a - b|
//   peak        = max b (the largest reference channel value over P)
//   psnr_db     = 20 log10(peak / rmse)
// HDR images have no fixed peak (1.0 or 255), so PSNR uses the reference's own largest value:
// it says how far the error sits below the brightest thing in the reference, and it changes
// when the reference is rescaled only through that value, never through the error. Edge cases:
// rmse = 0 gives psnr_db = +inf; a reference that is zero everywhere makes relative_l2 and
// psnr_db undefined (NaN, JSON null, with the "zero-reference" warning; rmse and max_abs still
// give the error). A non-finite value in either image
// makes the metrics NaN (it is never skipped) and is counted in non_finite.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <span>
#include <vector>

#include "prtlab/render/gbuffer.h"
#include "prtlab/image/image_io.h"

namespace prt {

struct ImageError {
  double relative_l2 = 0;
  double rmse = 0;
  double psnr_db = 0;
  double max_abs = 0;
  double peak = 0;             ///< the PSNR's peak: largest reference channel value over P
  std::size_t pixels = 0;      ///< |P|
  std::size_t non_finite = 0;  ///< counted pixels with a NaN or Inf channel in either image
};

/// Metrics of `image` against `reference` over the pixels where mask != 0 (mask empty: all).
/// ParameterError when the sizes differ (naming both) or the mask has the wrong length.
ImageError image_error(const RgbImage& image, const RgbImage& reference,
                       std::span<const std::uint8_t> mask = {});

/// The metrics as JSON (keys as in ImageError; a non-finite value becomes null).
nlohmann::json to_json(const ImageError& error);

/// 1 where the G-buffer has a hit (of `part`, when part >= 0), else 0; size width * height.
std::vector<std::uint8_t> hit_mask(const GBuffer& gbuffer, int part = -1);

/// Per-pixel relative error e = |a - b| / (|b| + eps) with |.| the Euclidean norm of the RGB
/// triple and eps = 1e-3 times the mean |b| over the counted pixels (so that black reference
/// pixels do not turn rounding noise into infinite relative error). 0 for pixels not counted.
/// Sizes are checked as in image_error. Returns width * height values, row-major.
std::vector<double> relative_error_map(const RgbImage& image, const RgbImage& reference,
                                       std::span<const std::uint8_t> mask = {});

/// Viridis (perceptually uniform, colour-blind safe, monotone in lightness) for t in [0, 1]
/// (clamped), as display values in [0, 1]: Matt Zucker's degree-6 polynomial fit of
/// matplotlib's table (max deviation about 0.01).
Rgb viridis(double t);

struct FalseColour {
  /// Display values in [0, 1] (already colour-mapped: write with gamma 1, no exposure, see
  /// write_false_colour_png). width x (height + colour bar).
  RgbImage image;
  double scale = 0;  ///< the relative error mapped to the top of the colour map
  double eps = 0;    ///< the eps of relative_error_map
};

/// The relative error map through viridis: e = 0 is dark purple, e >= scale bright yellow;
/// pixels not counted are dark grey (0.1). scale <= 0 picks the 99th percentile of e over the
/// counted pixels (the value of rank floor(0.99 (n - 1)) in increasing order; 1 when that is 0).
/// Below the image: 2 black rows, then a colour bar of max(8, height / 10) rows running from 0
/// (left) to scale (right), with white ticks at 0, 1/4, 1/2, 3/4 and 1 of the scale in its upper
/// half.
FalseColour error_false_colour(const RgbImage& image, const RgbImage& reference,
                               std::span<const std::uint8_t> mask = {}, double scale = 0);

/// Writes a FalseColour image as an 8-bit PNG without tone mapping (atomically).
void write_false_colour_png(const FalseColour& false_colour, const std::filesystem::path& file);

}  // namespace prt
