#pragma once
// Writing images: linear float EXR (OpenEXR) and tone-mapped 8-bit PNG (stb_image_write).
// Both are written atomically (temporary file, then rename).
#include <filesystem>
#include <vector>

#include "prtlab/sphere/cubemap.h"
#include "prtlab/base/types.h"

namespace prt {

struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<Rgb> pixels;  ///< row-major, row 0 at the top
  RgbImage() = default;
  RgbImage(int w, int h) : width(w), height(h), pixels(static_cast<std::size_t>(w) * h) {}
  Rgb& at(int x, int y) { return pixels[static_cast<std::size_t>(y) * width + x]; }
  const Rgb& at(int x, int y) const { return pixels[static_cast<std::size_t>(y) * width + x]; }
};

/// Float RGB EXR (ZIP compressed). Values are written bit-exactly.
void write_exr(const RgbImage& image, const std::filesystem::path& file);
/// Reads R, G, B (or luminance Y into all three; half or float, scanline or tiled) of an EXR's
/// data window as float. No value checks. InputError naming the file on any failure.
RgbImage read_exr(const std::filesystem::path& file);

/// PNG tone mapping, in this order: auto exposure, 2^exposure, optional Reinhard curve,
/// clamp to [0, 1], gamma, 8-bit quantisation.
struct ToneMap {
  double exposure = 0.0;  ///< stops; applied as 2^exposure before the curve
  bool auto_exposure =
      true;            ///< scale so the 99th-percentile luminance maps to 0.9 (before exposure)
  double gamma = 2.2;  ///< applied after Reinhard-style x / (1 + x) curve when `reinhard`
  bool reinhard = false;
};
void write_png(const RgbImage& image, const std::filesystem::path& file, const ToneMap& tm = {});
/// The display values write_png stores, before the 8-bit rounding: each channel in [0, 1]
/// (a non-finite or negative value becomes 0). For image comparisons on what a viewer sees
/// (ssim.h).
RgbImage tone_mapped(const RgbImage& image, const ToneMap& tm = {});

/// Cubemap as a horizontal cross (4R x 3R; unused cells black):
///          [+Y]
///     [-X] [+Z] [+X] [-Z]
///          [-Y]
/// Every face is copied as stored (column x, row y of the face image); in this cell order
/// adjacent faces then share their edges: the horizon runs
/// straight across -X, +Z, +X, -Z (and wraps from -Z back to -X), +Y's bottom edge meets +Z's
/// top. The cube face table (cubemap.h) is OpenGL's, which is left-handed, so the cross is the
/// mirror image of what a viewer at the centre sees in prtlab's right-handed world (compared
/// with the lat-long image, left and right are swapped). Only the picture is mirrored.
RgbImage cubemap_cross_image(const Cubemap& cubemap);
/// Cubemap as six faces side by side (6R x R), in face order, for EXR round trips.
RgbImage cubemap_strip_image(const Cubemap& cubemap);
/// Inverse of cubemap_strip_image (the image must be 6R x R). `source` names the file in errors.
Cubemap cubemap_from_strip_image(const RgbImage& strip, const std::filesystem::path& source = {});

}  // namespace prt
