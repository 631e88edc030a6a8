#include "prtlab/render/image_error.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "prtlab/base/error.h"
#include "prtlab/base/relative_error.h"

namespace prt {
namespace {

void check_shapes(const RgbImage& image, const RgbImage& reference,
                  std::span<const std::uint8_t> mask) {
  if (image.width != reference.width || image.height != reference.height) {
    throw ParameterError(fmt::format(
        "image error: the image is {} x {} but the reference is {} x {}; both must have the "
        "same size",
        image.width, image.height, reference.width, reference.height));
  }
  const std::size_t n = static_cast<std::size_t>(image.width) * image.height;
  PRT_CHECK(image.pixels.size() == n && reference.pixels.size() == n,
            "image pixel arrays do not match their sizes");
  if (!mask.empty() && mask.size() != n) {
    throw ParameterError(
        fmt::format("image error: the mask has {} entries but the images have {} x {} = {} pixels",
                    mask.size(), image.width, image.height, n));
  }
}

bool counted(std::span<const std::uint8_t> mask, std::size_t i) {
  return mask.empty() || mask[i] != 0;
}

double norm(const Rgb& v) {
  return std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
}

nlohmann::json finite_or_null(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

}  // namespace

ImageError image_error(const RgbImage& image, const RgbImage& reference,
                       std::span<const std::uint8_t> mask) {
  check_shapes(image, reference, mask);
  ImageError e;
  double sum_sq_diff = 0, sum_sq_ref = 0;
  // NaN must survive std::max, which would drop it: track it separately.
  bool nan_seen = false;
  for (std::size_t i = 0; i < image.pixels.size(); ++i) {
    if (!counted(mask, i)) continue;
    ++e.pixels;
    bool finite = true;
    for (int c = 0; c < 3; ++c) {
      const double a = image.pixels[i][c], b = reference.pixels[i][c];
      finite = finite && std::isfinite(a) && std::isfinite(b);
      const double d = a - b;
      sum_sq_diff += d * d;
      sum_sq_ref += b * b;
      if (std::isnan(d) || std::isnan(b)) nan_seen = true;
      e.max_abs = std::max(e.max_abs, std::abs(d));
      e.peak = std::max(e.peak, b);
    }
    if (!finite) ++e.non_finite;
  }
  if (e.pixels == 0) return e;
  if (e.non_finite > 0) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    e.relative_l2 = e.rmse = e.psnr_db = nan;
    if (nan_seen) e.max_abs = nan;
    return e;
  }
  const double inf = std::numeric_limits<double>::infinity();
  e.rmse = std::sqrt(sum_sq_diff / (3.0 * static_cast<double>(e.pixels)));
  e.relative_l2 =
      relative_to(std::sqrt(sum_sq_diff), std::sqrt(sum_sq_ref), "relative L2 error of an image");
  if (e.peak <= 0) {
    // A black reference has no peak: the PSNR is as undefined as the relative error.
    e.psnr_db = std::numeric_limits<double>::quiet_NaN();
  } else if (e.rmse == 0) {
    e.psnr_db = inf;
  } else {
    e.psnr_db = 20.0 * std::log10(e.peak / e.rmse);
  }
  return e;
}

nlohmann::json to_json(const ImageError& e) {
  return {{"relative_l2", finite_or_null(e.relative_l2)},
          {"rmse", finite_or_null(e.rmse)},
          {"psnr_db", finite_or_null(e.psnr_db)},
          {"max_abs", finite_or_null(e.max_abs)},
          {"peak", finite_or_null(e.peak)},
          {"pixels", e.pixels},
          {"non_finite", e.non_finite}};
}

std::vector<std::uint8_t> hit_mask(const GBuffer& gbuffer, int part) {
  std::vector<std::uint8_t> mask(gbuffer.pixel_count(), 0);
  for (std::size_t i = 0; i < mask.size(); ++i) {
    const bool hit = gbuffer.triangle[i] >= 0;
    mask[i] = hit && (part < 0 || gbuffer.part[i] == part) ? 1 : 0;
  }
  return mask;
}

namespace {

// eps of relative_error_map: 1e-3 of the mean reference norm over the counted pixels.
double relative_error_eps(const RgbImage& reference, std::span<const std::uint8_t> mask) {
  double sum = 0;
  std::size_t count = 0;
  for (std::size_t i = 0; i < reference.pixels.size(); ++i) {
    if (!counted(mask, i)) continue;
    const double n = norm(reference.pixels[i]);
    if (std::isfinite(n)) {
      sum += n;
      ++count;
    }
  }
  const double mean = count > 0 ? sum / static_cast<double>(count) : 0.0;
  // A reference that is black everywhere still needs a positive eps (no division by zero).
  return mean > 0 ? 1e-3 * mean : std::numeric_limits<double>::min();
}

std::vector<double> relative_error_map_with_eps(const RgbImage& image, const RgbImage& reference,
                                                std::span<const std::uint8_t> mask, double eps) {
  std::vector<double> e(image.pixels.size(), 0.0);
  for (std::size_t i = 0; i < e.size(); ++i) {
    if (!counted(mask, i)) continue;
    e[i] = norm(image.pixels[i] - reference.pixels[i]) / (norm(reference.pixels[i]) + eps);
  }
  return e;
}

}  // namespace

std::vector<double> relative_error_map(const RgbImage& image, const RgbImage& reference,
                                       std::span<const std::uint8_t> mask) {
  check_shapes(image, reference, mask);
  return relative_error_map_with_eps(image, reference, mask, relative_error_eps(reference, mask));
}

Rgb viridis(double t) {
  // Matt Zucker's least-squares polynomial fit of matplotlib's viridis (CC0,
  // https://www.shadertoy.com/view/WlfXRN), evaluated in Horner form.
  static constexpr double c[7][3] = {{0.2777273272234177, 0.005407344544966578, 0.3340998053353061},
                                     {0.1050930431085774, 1.404613529898575, 1.384590162594685},
                                     {-0.3308618287255563, 0.214847559468213, 0.09509516302823659},
                                     {-4.634230498983486, -5.799100973351585, -19.33244095627987},
                                     {6.228269936347081, 14.17993336680509, 56.69055260068105},
                                     {4.776384997670288, -13.74514537774601, -65.35303263337234},
                                     {-5.435455855934631, 4.645852612178535, 26.3124352495832}};
  const double x = std::isfinite(t) ? std::clamp(t, 0.0, 1.0) : 1.0;
  Rgb out;
  for (int ch = 0; ch < 3; ++ch) {
    double v = c[6][ch];
    for (int k = 5; k >= 0; --k) v = v * x + c[k][ch];
    out[ch] = static_cast<float>(std::clamp(v, 0.0, 1.0));
  }
  return out;
}

FalseColour error_false_colour(const RgbImage& image, const RgbImage& reference,
                               std::span<const std::uint8_t> mask, double scale) {
  check_shapes(image, reference, mask);
  FalseColour fc;
  fc.eps = relative_error_eps(reference, mask);
  const std::vector<double> e = relative_error_map_with_eps(image, reference, mask, fc.eps);

  if (!(scale > 0)) {
    std::vector<double> values;
    for (std::size_t i = 0; i < e.size(); ++i) {
      if (counted(mask, i) && std::isfinite(e[i])) values.push_back(e[i]);
    }
    double p99 = 0;
    if (!values.empty()) {
      const std::size_t k = static_cast<std::size_t>(0.99 * static_cast<double>(values.size() - 1));
      std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k),
                       values.end());
      p99 = values[k];
    }
    scale = p99 > 0 ? p99 : 1.0;
  }
  fc.scale = scale;

  const int w = image.width, h = image.height;
  const int separator = 2, bar = std::max(8, h / 10);
  fc.image = RgbImage(w, h + separator + bar);
  const Rgb not_counted(0.1f);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      fc.image.at(x, y) = counted(mask, i) ? viridis(e[i] / scale) : not_counted;
    }
  }
  for (int y = h; y < h + separator; ++y) {
    for (int x = 0; x < w; ++x) fc.image.at(x, y) = Rgb(0.f);
  }
  for (int x = 0; x < w; ++x) {
    const double t = w > 1 ? static_cast<double>(x) / (w - 1) : 0.0;
    const Rgb colour = viridis(t);
    for (int y = h + separator; y < h + separator + bar; ++y) fc.image.at(x, y) = colour;
  }
  for (int q = 0; q <= 4; ++q) {
    const int x = w > 1 ? static_cast<int>(std::lround(q * (w - 1) / 4.0)) : 0;
    for (int y = h + separator; y < h + separator + bar / 2; ++y) fc.image.at(x, y) = Rgb(1.f);
  }
  return fc;
}

void write_false_colour_png(const FalseColour& false_colour, const std::filesystem::path& file) {
  ToneMap identity;
  identity.auto_exposure = false;
  identity.exposure = 0.0;
  identity.gamma = 1.0;
  identity.reinhard = false;
  write_png(false_colour.image, file, identity);
}

}  // namespace prt
