#include "prtlab/sphere/hemisphere_grid.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "prtlab/base/error.h"

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

namespace {

// Integral of v -> max(u^2, v^2) over [v0, v1] for fixed u.
double max_square_inner(double u, double v0, double v1) {
  const double a = std::abs(u);
  const auto cube = [](double x) { return x * x * x / 3.0; };
  double s = 0.0;
  const double lo = std::max(v0, -a), hi = std::min(v1, a);
  if (hi > lo) s += u * u * (hi - lo);
  if (v0 < -a) s += cube(std::min(v1, -a)) - cube(v0);
  if (v1 > a) s += cube(v1) - cube(std::max(v0, a));
  return s;
}

// Integral of max(u^2, v^2) over [u0, u1] x [v0, v1]. The inner integral is a cubic in u between
// the breakpoints 0, +-|v0|, +-|v1|, so Simpson's rule on each piece is exact.
double max_square_integral(double u0, double u1, double v0, double v1) {
  std::vector<double> cuts{u0, u1};
  for (double c : {0.0, v0, -v0, v1, -v1})
    if (c > u0 && c < u1) cuts.push_back(c);
  std::sort(cuts.begin(), cuts.end());
  double sum = 0.0;
  for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
    const double a = cuts[i], b = cuts[i + 1];
    sum += (b - a) / 6.0 *
           (max_square_inner(a, v0, v1) + 4.0 * max_square_inner(0.5 * (a + b), v0, v1) +
            max_square_inner(b, v0, v1));
  }
  return sum;
}

}  // namespace

// z = 1 - r^2 and r^2 = max(u^2, v^2) in the concentric map's [-1, 1]^2 coordinates, where the
// map is area preserving with d(omega) = (pi / 2) du dv: P = (pi / 2) (area - int max(u^2, v^2)),
// integrated exactly.
std::vector<double> HemisphereGrid::projected_solid_angles() const {
  std::vector<double> out(static_cast<std::size_t>(s_) * s_, 0.0);
  const auto coord = [this](int i) { return 2.0 * i / s_ - 1.0; };
  for (int row = 0; row < s_; ++row)
    for (int col = 0; col < s_; ++col) {
      const double u0 = coord(col), u1 = coord(col + 1), v0 = coord(row), v1 = coord(row + 1);
      out[static_cast<std::size_t>(row) * s_ + col] =
          0.5 * kPi * ((u1 - u0) * (v1 - v0) - max_square_integral(u0, u1, v0, v1));
    }
  return out;
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
