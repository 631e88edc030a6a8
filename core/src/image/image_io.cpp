#include "prtlab/image/image_io.h"

#include <ImathBox.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <exception>
#include <span>
#include <string>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/storage/atomic_file.h"

#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

namespace prt {
namespace fs = std::filesystem;

// The EXR slices below address the channels of an Rgb array with a stride of one Rgb.
static_assert(sizeof(Rgb) == 3 * sizeof(float), "Rgb must be three tightly packed floats");

namespace {

void check_image(const RgbImage& image, const fs::path& file) {
  if (image.width <= 0 || image.height <= 0) {
    throw ParameterError(fmt::format("{}: cannot write an empty image ({} x {})", file.string(),
                                     image.width, image.height));
  }
  PRT_CHECK(image.pixels.size() == static_cast<std::size_t>(image.width) * image.height,
            "image has {} pixels, {} x {} expected", image.pixels.size(), image.width,
            image.height);
}

float luminance(const Rgb& c) {
  return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b;
}

}  // namespace

void write_exr(const RgbImage& image, const fs::path& file) {
  check_image(image, file);
  write_file_atomically(file, [&](const fs::path& tmp) {
    try {
      Imf::Header header(image.width, image.height);
      header.compression() = Imf::ZIP_COMPRESSION;
      for (const char* name : {"R", "G", "B"})
        header.channels().insert(name, Imf::Channel(Imf::FLOAT));
      // OpenEXR's Slice wants a non-const base even for writing; it only reads through it.
      char* base = reinterpret_cast<char*>(const_cast<Rgb*>(image.pixels.data()));
      const std::size_t xs = sizeof(Rgb), ys = sizeof(Rgb) * image.width;
      Imf::FrameBuffer fb;
      fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
      fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
      fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
      // The file is closed (line offsets written) when `out` goes out of scope, before the
      // rename in write_file_atomically.
      Imf::OutputFile out(tmp.c_str(), header);
      out.setFrameBuffer(fb);
      out.writePixels(image.height);
    } catch (const Error&) {
      throw;
    } catch (const std::exception& e) {
      throw InputError(file, fmt::format("cannot write OpenEXR file: {}", e.what()));
    }
  });
}

// 16384 x 8192, the largest lat-long maps published (1.6 GB as float RGB).
constexpr long long kMaxExrPixels = 16384LL * 8192;

RgbImage read_exr(const fs::path& file) {
  std::error_code ec;
  if (!fs::exists(file, ec)) throw InputError(file, "file not found");
  if (!fs::is_regular_file(file, ec)) throw InputError(file, "not a regular file");
  try {
    Imf::InputFile in(file.c_str());
    const Imath::Box2i dw = in.header().dataWindow();
    const long long w = static_cast<long long>(dw.max.x) - dw.min.x + 1;
    const long long h = static_cast<long long>(dw.max.y) - dw.min.y + 1;
    if (w <= 0 || h <= 0 || w * h > kMaxExrPixels) {
      throw InputError(file, fmt::format("unsupported EXR data window {} x {} (at most {} pixels)",
                                         w, h, kMaxExrPixels));
    }
    const Imf::ChannelList& channels = in.header().channels();
    const bool has_rgb =
        channels.findChannel("R") && channels.findChannel("G") && channels.findChannel("B");
    const bool has_y = channels.findChannel("Y") != nullptr;
    if (!has_rgb && !has_y) {
      std::string names;
      for (auto it = channels.begin(); it != channels.end(); ++it) {
        names += (names.empty() ? "" : ", ") + std::string(it.name());
      }
      throw InputError(file, fmt::format("EXR has no R, G, B (or Y) channels; its channels are: {}",
                                         names.empty() ? "(none)" : names));
    }
    // Decoded in strips, the image growing as they arrive: a header can declare any size, so
    // memory follows the pixels actually in the file, and a truncated or lying file fails at
    // its first missing strip instead of after allocating the whole declared image.
    RgbImage image;
    image.width = static_cast<int>(w);
    image.height = static_cast<int>(h);
    constexpr long long kStripRows = 64;
    image.pixels.reserve(static_cast<std::size_t>(std::min(w * h, w * kStripRows * 16)));
    std::vector<Rgb> strip(static_cast<std::size_t>(w * std::min(h, kStripRows)));
    const std::size_t xs = sizeof(Rgb), ys = sizeof(Rgb) * static_cast<std::size_t>(w);
    for (int y0 = dw.min.y; y0 <= dw.max.y;) {
      const int y1 = static_cast<int>(std::min<long long>(dw.max.y, y0 + kStripRows - 1));
      const Imath::Box2i window(Imath::V2i(dw.min.x, y0), Imath::V2i(dw.max.x, y1));
      char* base = reinterpret_cast<char*>(strip.data());
      Imf::FrameBuffer fb;
      auto slice = [&](std::size_t channel) {
        return Imf::Slice::Make(Imf::FLOAT, base + channel * sizeof(float), window, xs, ys);
      };
      if (has_rgb) {
        fb.insert("R", slice(0));
        fb.insert("G", slice(1));
        fb.insert("B", slice(2));
      } else {
        fb.insert("Y", slice(0));
      }
      in.setFrameBuffer(fb);
      in.readPixels(y0, y1);
      image.pixels.insert(image.pixels.end(), strip.begin(),
                          strip.begin() + static_cast<std::ptrdiff_t>(w * (y1 - y0 + 1)));
      y0 = y1 + 1;
    }
    if (!has_rgb) {
      for (Rgb& p : image.pixels) p.g = p.b = p.r;
    }
    return image;
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(
        file, fmt::format("cannot read as OpenEXR (not an EXR, or truncated): {}", e.what()));
  }
}

namespace {

// The scale before the curve: 2^exposure, times the auto exposure's.
double display_scale(const RgbImage& image, const ToneMap& tm) {
  double scale = std::exp2(tm.exposure);
  if (tm.auto_exposure) {
    std::vector<float> lum;
    lum.reserve(image.pixels.size());
    for (const Rgb& p : image.pixels) {
      const float l = luminance(p);
      if (std::isfinite(l)) lum.push_back(std::max(l, 0.f));
    }
    float p99 = 0.f;
    if (!lum.empty()) {
      const std::size_t i = std::min(lum.size() - 1, static_cast<std::size_t>(0.99 * lum.size()));
      std::nth_element(lum.begin(), lum.begin() + static_cast<std::ptrdiff_t>(i), lum.end());
      p99 = lum[i];
      // A mostly black image (a cross has half its area unused) still needs an exposure.
      if (p99 <= 0.f) p99 = *std::max_element(lum.begin(), lum.end());
    }
    if (p99 > 0.f) scale *= 0.9 / p99;
  }
  return scale;
}

double display_value(float value, double scale, const ToneMap& tm) {
  const double inv_gamma = tm.gamma > 0.0 ? 1.0 / tm.gamma : 1.0;
  double x = value * scale;
  if (!std::isfinite(x) || x < 0.0) x = 0.0;
  if (tm.reinhard) x = x / (1.0 + x);
  return std::pow(std::min(x, 1.0), inv_gamma);
}

}  // namespace

RgbImage tone_mapped(const RgbImage& image, const ToneMap& tm) {
  const double scale = display_scale(image, tm);
  RgbImage out(image.width, image.height);
  out.pixels.resize(image.pixels.size());
  for (std::size_t i = 0; i < image.pixels.size(); ++i)
    for (int c = 0; c < 3; ++c)
      out.pixels[i][c] = static_cast<float>(display_value(image.pixels[i][c], scale, tm));
  return out;
}

void write_png(const RgbImage& image, const fs::path& file, const ToneMap& tm) {
  check_image(image, file);
  const double scale = display_scale(image, tm);
  std::vector<unsigned char> rgb(image.pixels.size() * 3);
  for (std::size_t i = 0; i < image.pixels.size(); ++i)
    for (int c = 0; c < 3; ++c)
      rgb[3 * i + c] = static_cast<unsigned char>(
          std::lround(display_value(image.pixels[i][c], scale, tm) * 255.0));
  std::vector<unsigned char> png;
  auto append = [](void* ctx, void* data, int size) {
    auto* out = static_cast<std::vector<unsigned char>*>(ctx);
    const auto* bytes = static_cast<const unsigned char*>(data);
    out->insert(out->end(), bytes, bytes + size);
  };
  if (!stbi_write_png_to_func(append, &png, image.width, image.height, 3, rgb.data(),
                              image.width * 3)) {
    throw InputError(file, "PNG encoding failed");
  }
  write_bytes_atomically(file, std::as_bytes(std::span(png.data(), png.size())));
}

RgbImage cubemap_cross_image(const Cubemap& cubemap) {
  const int r = cubemap.layout.resolution();
  RgbImage image(4 * r, 3 * r);
  // (face, cell column, cell row) of the cross; see image_io.h.
  constexpr int kCells[6][3] = {{0, 2, 1}, {1, 0, 1}, {2, 1, 0}, {3, 1, 2}, {4, 1, 1}, {5, 3, 1}};
  for (const auto& [face, cx, cy] : kCells) {
    for (int y = 0; y < r; ++y) {
      for (int x = 0; x < r; ++x) {
        image.at(cx * r + x, cy * r + y) = cubemap.radiance[cubemap.layout.index(face, x, y)];
      }
    }
  }
  return image;
}

RgbImage cubemap_strip_image(const Cubemap& cubemap) {
  const int r = cubemap.layout.resolution();
  RgbImage image(6 * r, r);
  for (int face = 0; face < 6; ++face) {
    for (int y = 0; y < r; ++y) {
      for (int x = 0; x < r; ++x) {
        image.at(face * r + x, y) = cubemap.radiance[cubemap.layout.index(face, x, y)];
      }
    }
  }
  return image;
}

Cubemap cubemap_from_strip_image(const RgbImage& strip, const fs::path& source) {
  const int r = strip.height;
  if (r <= 0 || strip.width != 6 * r) {
    throw InputError(source, fmt::format("a cubemap strip must be 6R x R pixels, got {} x {}",
                                         strip.width, strip.height));
  }
  Cubemap cubemap(r);
  for (int face = 0; face < 6; ++face) {
    for (int y = 0; y < r; ++y) {
      for (int x = 0; x < r; ++x) {
        cubemap.radiance[cubemap.layout.index(face, x, y)] = strip.at(face * r + x, y);
      }
    }
  }
  return cubemap;
}

}  // namespace prt
