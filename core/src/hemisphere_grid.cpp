#include "prtlab/hemisphere_grid.h"

#include <algorithm>
#include <cmath>

#include "prtlab/error.h"

namespace prt {

namespace {
constexpr double kQuarterPi = kPi / 4.0;
}  // namespace

// Shirley and Chiu 1997, "A low distortion map between disk and square". The square
// [-1,1]^2 is split by its diagonals into four triangles; in each, the coordinate of larger
// magnitude becomes the (signed) radius and the ratio of the two the angle. On a diagonal
// both branches give the same point, so the map is continuous.
Vec2d square_to_disk_concentric(const Vec2d& ab) {
  const double u = 2.0 * ab.x - 1.0;
  const double v = 2.0 * ab.y - 1.0;
  if (u == 0.0 && v == 0.0) return {0.0, 0.0};
  double r = 0.0, phi = 0.0;
  if (std::abs(u) > std::abs(v)) {
    r = u;
    phi = kQuarterPi * (v / u);
  } else {
    r = v;
    phi = 2.0 * kQuarterPi - kQuarterPi * (u / v);
  }
  return {r * std::cos(phi), r * std::sin(phi)};
}

Vec2d disk_to_square_concentric(const Vec2d& xy) {
  const double r = std::hypot(xy.x, xy.y);
  if (r == 0.0) return {0.5, 0.5};
  double phi = std::atan2(xy.y, xy.x);      // (-pi, pi]
  if (phi < -kQuarterPi) phi += 2.0 * kPi;  // now in [-pi/4, 7pi/4)
  double u = 0.0, v = 0.0;
  if (phi < kQuarterPi) {  // right triangle: u = r
    u = r;
    v = phi / kQuarterPi * u;
  } else if (phi < 3.0 * kQuarterPi) {  // top: v = r
    v = r;
    u = (2.0 * kQuarterPi - phi) / kQuarterPi * v;
  } else if (phi < 5.0 * kQuarterPi) {  // left: u = -r, the forward angle was phi - pi
    u = -r;
    v = (phi - 4.0 * kQuarterPi) / kQuarterPi * u;
  } else {  // bottom: v = -r, the forward angle was phi - pi
    v = -r;
    u = (6.0 * kQuarterPi - phi) / kQuarterPi * v;
  }
  return {0.5 * (u + 1.0), 0.5 * (v + 1.0)};
}

Vec3d square_to_hemisphere(const Vec2d& ab) {
  const Vec2d p = square_to_disk_concentric(ab);
  // r^2 may exceed 1 by an ulp at the square's boundary; the clamp keeps z >= 0.
  const double r2 = std::min(p.x * p.x + p.y * p.y, 1.0);
  const double f = std::sqrt(2.0 - r2);
  return {p.x * f, p.y * f, 1.0 - r2};
}

Vec2d hemisphere_to_square(const Vec3d& d) {
  const Vec3d u = glm::normalize(d);
  // The forward map has 1 + z = 2 - r^2, so the disk point is xy / sqrt(1 + z); this form
  // keeps full precision near the pole, where 1 - z would cancel.
  const double inv = 1.0 / std::sqrt(1.0 + std::abs(u.z));
  return disk_to_square_concentric({u.x * inv, u.y * inv});
}

HemisphereGrid::HemisphereGrid(int side) : s_(side) {
  if (side < 1 || side > 4096) {
    throw ParameterError(fmt::format("hemisphere grid side must be in [1, 4096], got {}", side));
  }
  directions_.resize(static_cast<std::size_t>(s_) * s_);
  for (int row = 0; row < s_; ++row)
    for (int col = 0; col < s_; ++col)
      directions_[row * s_ + col] = square_to_hemisphere({(col + 0.5) / s_, (row + 0.5) / s_});
}

double HemisphereGrid::cell_solid_angle() const {
  return kTwoPi / (static_cast<double>(s_) * s_);
}

int HemisphereGrid::cell_of(const Vec3d& d) const {
  if (!(d.z > 0.0)) return -1;  // also rejects NaN
  const Vec2d ab = hemisphere_to_square(d);
  if (!std::isfinite(ab.x) || !std::isfinite(ab.y)) return -1;
  // Clamp: a = 1 exactly (the square's edge) belongs to the last cell, and rounding may put
  // a or b a hair outside [0, 1].
  const int col = std::clamp(static_cast<int>(std::floor(ab.x * s_)), 0, s_ - 1);
  const int row = std::clamp(static_cast<int>(std::floor(ab.y * s_)), 0, s_ - 1);
  return row * s_ + col;
}

}  // namespace prt
