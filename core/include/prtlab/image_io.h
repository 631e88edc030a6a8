#pragma once
// Writing images: linear float EXR (OpenEXR) and tone-mapped 8-bit PNG (stb_image_write).
// Both are written atomically (temporary file, then rename).
#include <filesystem>
#include <vector>

#include "prtlab/cubemap.h"
#include "prtlab/types.h"

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

void write_exr(const RgbImage& image, const std::filesystem::path& file);
RgbImage read_exr(const std::filesystem::path& file);

struct ToneMap {
  double exposure = 0.0;   ///< stops; applied as 2^exposure before the curve
  bool auto_exposure = true;  ///< scale so the 99th-percentile luminance maps to 0.9 (before exposure)
  double gamma = 2.2;      ///< applied after Reinhard-style x / (1 + x) curve when `reinhard`
  bool reinhard = false;
};
void write_png(const RgbImage& image, const std::filesystem::path& file, const ToneMap& tm = {});

/// Cubemap as a horizontal cross (4R x 3R; unused cells black):
///          [+Y]
///     [-X] [+Z] [+X] [-Z]
///          [-Y]
/// oriented so the cross folds into a cube seen from inside.
RgbImage cubemap_cross_image(const Cubemap& cubemap);
/// Cubemap as six faces side by side (6R x R), in face order, for EXR round trips.
RgbImage cubemap_strip_image(const Cubemap& cubemap);

}  // namespace prt
