#include "prtlab/sphere/spherical_harmonics.h"

#include <tbb/parallel_for.h>

#include <array>
#include <cmath>

#include "prtlab/base/error.h"

namespace prt {

namespace {

// norm[l][m] = K_l^m for m = 0 and sqrt(2) K_l^m for m > 0, with
// K_l^m = sqrt((2l + 1) / (4 pi) (l - m)! / (l + m)!).
struct ShNorms {
  std::array<std::array<double, kMaxShOrder>, kMaxShOrder> norm{};
  ShNorms() {
    for (int l = 0; l < kMaxShOrder; ++l) {
      for (int m = 0; m <= l; ++m) {
        double ratio = 1.0;  // (l - m)! / (l + m)!
        for (int i = l - m + 1; i <= l + m; ++i) ratio /= i;
        const double k = std::sqrt((2.0 * l + 1.0) / (4.0 * kPi) * ratio);
        norm[l][m] = m == 0 ? k : std::sqrt(2.0) * k;
      }
    }
  }
};

const ShNorms& sh_norms() {
  static const ShNorms norms;
  return norms;
}

void check_order(int order) {
  if (order < 1 || order > kMaxShOrder) {
    throw ParameterError(
        fmt::format("spherical harmonics order must be in [1, {}], got {}", kMaxShOrder, order));
  }
}

}  // namespace

// Cartesian form: sin^m(theta) cos(m phi) + i sin^m(theta) sin(m phi) = (x + i y)^m, and
// Q_l^m(z) = P_l^m(z) / sin^m(theta) satisfies the same three-term recurrence in l as P_l^m
// (stable upward in l for fixed m) starting from Q_m^m = (2m - 1)!!. No trigonometric calls,
// no sqrt(1 - z^2), and exact at the poles.
void sh_eval(int order, const Vec3d& d, std::span<double> out) {
  PRT_CHECK(order >= 1 && order <= kMaxShOrder, "SH order {} out of range", order);
  PRT_CHECK(out.size() >= static_cast<std::size_t>(sh_count(order)), "SH output span too small");
  const auto& norm = sh_norms().norm;
  const double x = d.x, y = d.y, z = d.z;
  double c = 1.0, s = 0.0;  // Re and Im of (x + i y)^m
  double qmm = 1.0;         // Q_m^m
  for (int m = 0; m < order; ++m) {
    if (m > 0) {
      qmm *= 2.0 * m - 1.0;
      const double cn = c * x - s * y;
      s = c * y + s * x;
      c = cn;
    }
    double q2 = 0.0, q1 = 0.0;  // Q_{l-2}^m, Q_{l-1}^m
    for (int l = m; l < order; ++l) {
      double q;
      if (l == m) {
        q = qmm;
      } else if (l == m + 1) {
        q = (2.0 * m + 1.0) * z * qmm;
      } else {
        q = ((2.0 * l - 1.0) * z * q1 - (l + m - 1.0) * q2) / (l - m);
      }
      q2 = q1;
      q1 = q;
      const double kq = norm[l][m] * q;
      if (m == 0) {
        out[sh_index(l, 0)] = kq;
      } else {
        out[sh_index(l, m)] = kq * c;
        out[sh_index(l, -m)] = kq * s;
      }
    }
  }
}

ShCoeffs sh_project(const Cubemap& radiance, int order) {
  check_order(order);
  const CubemapLayout& layout = radiance.layout;
  PRT_CHECK(radiance.radiance.size() == static_cast<std::size_t>(layout.pixel_count()),
            "cubemap radiance has {} entries, layout needs {}", radiance.radiance.size(),
            layout.pixel_count());
  const int n = sh_count(order);
  const int r2 = layout.resolution() * layout.resolution();
  const auto dirs = layout.directions();
  const auto omega = layout.solid_angles();

  // One partial sum per face, added in face order: parallel yet bit-for-bit deterministic.
  std::array<std::vector<Vec3d>, 6> partial;
  tbb::parallel_for(0, 6, [&](int face) {
    std::vector<Vec3d>& acc = partial[face];
    acc.assign(n, Vec3d{0.0});
    std::array<double, sh_count(kMaxShOrder)> y{};
    for (int k = face * r2; k < (face + 1) * r2; ++k) {
      const Vec3d w = Vec3d(radiance.radiance[k]) * omega[k];
      if (w == Vec3d{0.0}) continue;
      sh_eval(order, dirs[k], y);
      for (int i = 0; i < n; ++i) acc[i] += w * y[i];
    }
  });

  ShCoeffs out;
  out.order = order;
  out.coeffs.assign(n, Vec3d{0.0});
  for (const auto& acc : partial)
    for (int i = 0; i < n; ++i) out.coeffs[i] += acc[i];
  return out;
}

Vec3d sh_evaluate(const ShCoeffs& c, const Vec3d& d) {
  check_order(c.order);
  PRT_CHECK(c.coeffs.size() == static_cast<std::size_t>(sh_count(c.order)),
            "SH expansion of order {} has {} coefficients", c.order, c.coeffs.size());
  std::array<double, sh_count(kMaxShOrder)> y{};
  sh_eval(c.order, d, y);
  Vec3d sum{0.0};
  for (int i = 0; i < sh_count(c.order); ++i) sum += c.coeffs[i] * y[i];
  return sum;
}

}  // namespace prt
