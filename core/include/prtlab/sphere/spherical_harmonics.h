#pragma once
// Real spherical harmonics y_i, i = l (l + 1) + m, for orders up to 10 (bands l < order,
// n = order^2 functions), orthonormal on the unit sphere, z the polar axis. Sign convention:
// no Condon-Shortley phase, so that for l = 1
//   y_0 = 1 / (2 sqrt(pi)),
//   y_1 = sqrt(3 / (4 pi)) y,  y_2 = sqrt(3 / (4 pi)) z,  y_3 = sqrt(3 / (4 pi)) x,
// and in general y_{l,m} = sqrt(2) K_l^m cos(m phi) P_l^m(cos theta) for m > 0,
// sqrt(2) K_l^|m| sin(|m| phi) P_l^|m|(cos theta) for m < 0, K_l^0 P_l^0 for m = 0,
// with P_l^m the associated Legendre functions without the (-1)^m factor.
#include <span>
#include <vector>

#include "prtlab/sphere/cubemap.h"
#include "prtlab/base/types.h"

namespace prt {

inline constexpr int kMaxShOrder = 10;

constexpr int sh_count(int order) {
  return order * order;
}
constexpr int sh_index(int l, int m) {
  return l * (l + 1) + m;
}

/// Evaluate all order^2 real SH at unit direction d into out (size >= order^2). d must be
/// unit length (not normalised here: this is the inner loop of projections). Lower orders
/// are a prefix of higher ones, value for value.
void sh_eval(int order, const Vec3d& d, std::span<double> out);

/// SH coefficients per channel (size order^2 each), projected by cubemap quadrature:
/// c_i = sum_k L_k y_i(d_k) solidAngle_k.
struct ShCoeffs {
  int order = 0;
  std::vector<Vec3d> coeffs;  ///< RGB per coefficient, size order^2
};
/// Throws ParameterError unless 1 <= order <= kMaxShOrder. Deterministic (partial sums per
/// face, added in face order).
ShCoeffs sh_project(const Cubemap& radiance, int order);
/// Evaluate an SH expansion at unit direction d.
Vec3d sh_evaluate(const ShCoeffs& c, const Vec3d& d);

}  // namespace prt
