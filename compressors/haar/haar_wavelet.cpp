#include "haar/haar_wavelet.h"

#include <algorithm>

#include "prtlab/base/error.h"

namespace prt::haar {
namespace {

void check_face(std::span<double> face, int resolution, std::span<double> scratch) {
  PRT_CHECK(is_power_of_two(resolution) &&
                face.size() == static_cast<std::size_t>(resolution) * resolution &&
                scratch.size() >= face.size(),
            "haar face transform: R = {}, face {} values, scratch {}", resolution, face.size(),
            scratch.size());
}

}  // namespace

bool is_power_of_two(int resolution) {
  return resolution >= 1 && (resolution & (resolution - 1)) == 0;
}

HaarSupport haar_support(int resolution, int x, int y) {
  PRT_CHECK(is_power_of_two(resolution) && x >= 0 && y >= 0 && x < resolution && y < resolution,
            "haar_support: ({}, {}) at R = {}", x, y, resolution);
  HaarSupport s;
  if (x == 0 && y == 0) {
    s.size = resolution;
    return s;
  }
  int level = 1;  // the s of the header
  while (2 * level <= std::max(x, y)) level *= 2;
  s.size = resolution / level;
  s.split_x = x >= level;
  s.split_y = y >= level;
  s.x0 = (s.split_x ? x - level : x) * s.size;
  s.y0 = (s.split_y ? y - level : y) * s.size;
  return s;
}

// One level of the transform is a 2 x 2 butterfly per group of the s x s block: with
// p = a + b, q = a - b, r = c + d, t = c - d (a, b the group's top row), the sums (p + r) / 2 go to
// the top-left (s/2)^2 block, (q + t) / 2 to the top-right, (p - r) / 2 to the bottom-left and
// (q - t) / 2 to the bottom-right: exactly GSL's row step followed by its column step, in 12
// FLOPs per group instead of 16.
void forward_face(std::span<double> face, int resolution, std::span<double> scratch) {
  check_face(face, resolution, scratch);
  const int r = resolution;
  for (int s = r; s >= 2; s /= 2) {
    const int h = s / 2;
    for (int j = 0; j < h; ++j) {
      const double* top = &face[static_cast<std::size_t>(2 * j) * r];
      const double* bottom = top + r;
      for (int i = 0; i < h; ++i) {
        const double p = top[2 * i] + top[2 * i + 1], q = top[2 * i] - top[2 * i + 1];
        const double u = bottom[2 * i] + bottom[2 * i + 1], t = bottom[2 * i] - bottom[2 * i + 1];
        scratch[j * s + i] = 0.5 * (p + u);
        scratch[j * s + i + h] = 0.5 * (q + t);
        scratch[(j + h) * s + i] = 0.5 * (p - u);
        scratch[(j + h) * s + i + h] = 0.5 * (q - t);
      }
    }
    for (int y = 0; y < s; ++y)
      std::copy_n(&scratch[static_cast<std::size_t>(y) * s], s,
                  &face[static_cast<std::size_t>(y) * r]);
  }
}

void inverse_face(std::span<double> face, int resolution, std::span<double> scratch) {
  check_face(face, resolution, scratch);
  const int r = resolution;
  for (int s = 2; s <= r; s *= 2) {
    const int h = s / 2;
    for (int j = 0; j < h; ++j) {
      const double* row_sum = &face[static_cast<std::size_t>(j) * r];
      const double* row_diff = &face[static_cast<std::size_t>(j + h) * r];
      for (int i = 0; i < h; ++i) {
        const double p = row_sum[i] + row_diff[i], u = row_sum[i] - row_diff[i];
        const double q = row_sum[i + h] + row_diff[i + h], t = row_sum[i + h] - row_diff[i + h];
        scratch[2 * j * s + 2 * i] = 0.5 * (p + q);
        scratch[2 * j * s + 2 * i + 1] = 0.5 * (p - q);
        scratch[(2 * j + 1) * s + 2 * i] = 0.5 * (u + t);
        scratch[(2 * j + 1) * s + 2 * i + 1] = 0.5 * (u - t);
      }
    }
    for (int y = 0; y < s; ++y)
      std::copy_n(&scratch[static_cast<std::size_t>(y) * s], s,
                  &face[static_cast<std::size_t>(y) * r]);
  }
}

namespace {
template <typename Fn>
void each_face(std::span<double> values, int resolution, const Fn& fn) {
  const std::size_t face = static_cast<std::size_t>(resolution) * resolution;
  PRT_CHECK(is_power_of_two(resolution) && values.size() == 6 * face,
            "haar cubemap transform: {} values at R = {}", values.size(), resolution);
  std::vector<double> scratch(face);
  for (int f = 0; f < 6; ++f) fn(values.subspan(f * face, face), resolution, std::span(scratch));
}
}  // namespace

void forward_cubemap(std::span<double> values, int resolution) {
  each_face(values, resolution, forward_face);
}

void inverse_cubemap(std::span<double> values, int resolution) {
  each_face(values, resolution, inverse_face);
}

std::vector<double> support_solid_angles(const CubemapLayout& layout) {
  const int r = layout.resolution();
  if (!is_power_of_two(r))
    throw ParameterError(fmt::format(
        "haar: the cubemap resolution R = {} is not a power of two (the Haar transform halves "
        "each face down to one pixel)",
        r));
  const auto omega = layout.solid_angles();
  std::vector<double> out(omega.size());
  for (int f = 0; f < 6; ++f)
    for (int y = 0; y < r; ++y)
      for (int x = 0; x < r; ++x) {
        const HaarSupport s = haar_support(r, x, y);
        double sum = 0;
        for (int v = s.y0; v < s.y0 + s.size; ++v)
          for (int u = s.x0; u < s.x0 + s.size; ++u) sum += omega[layout.index(f, u, v)];
        out[layout.index(f, x, y)] = sum;
      }
  return out;
}

double transform_flops(int resolution) {
  const double r2 = static_cast<double>(resolution) * resolution;
  return 6.0 * 12.0 * (r2 - 1.0) / 3.0;
}

}  // namespace prt::haar
