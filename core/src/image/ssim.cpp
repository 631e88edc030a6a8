#include "prtlab/image/ssim.h"

#include <fmt/format.h>

#include <cmath>
#include <cstddef>

#include "prtlab/base/error.h"

namespace prt {

namespace {

// Separable weighted mean over the window, cut at the border: the cut 2D window's weight sum is
// the product of the two 1D sums, so normalising each pass by its own sum is exact.
void blur_rows(std::vector<double>& plane, int w, int h, const std::vector<double>& g, int r) {
  std::vector<double> out(plane.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double sum = 0, weight = 0;
      for (int k = -r; k <= r; ++k) {
        const int xx = x + k;
        if (xx < 0 || xx >= w) continue;
        const double gk = g[static_cast<std::size_t>(k + r)];
        sum += gk * plane[static_cast<std::size_t>(y) * w + xx];
        weight += gk;
      }
      out[static_cast<std::size_t>(y) * w + x] = sum / weight;
    }
  plane.swap(out);
}

void blur_columns(std::vector<double>& plane, int w, int h, const std::vector<double>& g, int r) {
  std::vector<double> out(plane.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double sum = 0, weight = 0;
      for (int k = -r; k <= r; ++k) {
        const int yy = y + k;
        if (yy < 0 || yy >= h) continue;
        const double gk = g[static_cast<std::size_t>(k + r)];
        sum += gk * plane[static_cast<std::size_t>(yy) * w + x];
        weight += gk;
      }
      out[static_cast<std::size_t>(y) * w + x] = sum / weight;
    }
  plane.swap(out);
}

}  // namespace

std::vector<double> ssim_map(const RgbImage& image, const RgbImage& reference,
                             const SsimOptions& o) {
  if (image.width != reference.width || image.height != reference.height)
    throw ParameterError(fmt::format("ssim: image is {} x {}, reference {} x {}", image.width,
                                     image.height, reference.width, reference.height));
  if (image.width <= 0 || image.height <= 0) throw ParameterError("ssim: empty image");
  if (!(o.sigma > 0) || o.radius < 0 || !(o.data_range > 0))
    throw ParameterError(
        fmt::format("ssim: sigma {} must be > 0, radius {} >= 0, data_range {} > 0", o.sigma,
                    o.radius, o.data_range));
  const int w = image.width, h = image.height, r = o.radius;
  const std::size_t n = static_cast<std::size_t>(w) * h;
  std::vector<double> g(static_cast<std::size_t>(2 * r + 1));
  for (int k = -r; k <= r; ++k)
    g[static_cast<std::size_t>(k + r)] = std::exp(-0.5 * k * k / (o.sigma * o.sigma));
  const double c1 = (o.k1 * o.data_range) * (o.k1 * o.data_range);
  const double c2 = (o.k2 * o.data_range) * (o.k2 * o.data_range);
  std::vector<double> out(n, 0.0);
  for (int c = 0; c < 3; ++c) {
    std::vector<double> mx(n), my(n), xx(n), yy(n), xy(n);
    for (std::size_t i = 0; i < n; ++i) {
      const double a = image.pixels[i][c], b = reference.pixels[i][c];
      mx[i] = a;
      my[i] = b;
      xx[i] = a * a;
      yy[i] = b * b;
      xy[i] = a * b;
    }
    for (auto* plane : {&mx, &my, &xx, &yy, &xy}) {
      blur_rows(*plane, w, h, g, r);
      blur_columns(*plane, w, h, g, r);
    }
    for (std::size_t i = 0; i < n; ++i) {
      const double vx = xx[i] - mx[i] * mx[i], vy = yy[i] - my[i] * my[i];
      const double cov = xy[i] - mx[i] * my[i];
      const double s = (2 * mx[i] * my[i] + c1) * (2 * cov + c2) /
                       ((mx[i] * mx[i] + my[i] * my[i] + c1) * (vx + vy + c2));
      out[i] += s / 3.0;
    }
  }
  return out;
}

double ssim(const RgbImage& image, const RgbImage& reference, std::span<const std::uint8_t> mask,
            const SsimOptions& options) {
  const std::vector<double> map = ssim_map(image, reference, options);
  if (!mask.empty() && mask.size() != map.size())
    throw ParameterError(
        fmt::format("ssim: mask has {} entries, the image {} pixels", mask.size(), map.size()));
  double sum = 0;
  std::size_t count = 0;
  for (std::size_t i = 0; i < map.size(); ++i)
    if (mask.empty() || mask[i]) {
      sum += map[i];
      ++count;
    }
  if (count == 0) throw ParameterError("ssim: the mask counts no pixel");
  return sum / static_cast<double>(count);
}

}  // namespace prt
