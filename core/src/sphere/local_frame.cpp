#include "prtlab/sphere/local_frame.h"

#include <cmath>

#include "prtlab/base/error.h"

namespace prt {

// Duff, Burgess, Christensen, Hery, Kensler, Liani, Villemin 2017, "Building an Orthonormal
// Basis, Revisited" (JCGT 6(1)), listing 3. copysign rather than a threshold on n.z keeps the
// frame continuous everywhere except across the plane z = 0 and exact at n = +-z.
LocalFrame LocalFrame::from_normal(const Vec3d& normal) {
  const double len = glm::length(normal);
  PRT_CHECK(len > 0.0 && std::isfinite(len), "frame normal must be finite and non-zero");
  const Vec3d n = normal / len;
  const double sign = std::copysign(1.0, n.z);
  const double a = -1.0 / (sign + n.z);
  const double b = n.x * n.y * a;
  LocalFrame f;
  f.t = {1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x};
  f.b = {b, sign + n.y * n.y * a, -n.y};
  f.n = n;
  return f;
}

LocalFrame LocalFrame::from_normal_tangent(const Vec3d& normal, const Vec3d& tangent) {
  const double len = glm::length(normal);
  PRT_CHECK(len > 0.0 && std::isfinite(len), "frame normal must be finite and non-zero");
  return from_unit_normal_tangent(normal / len, tangent);
}

LocalFrame LocalFrame::from_unit_normal_tangent(const Vec3d& n, const Vec3d& tangent) {
  Vec3d t = tangent - n * glm::dot(n, tangent);
  // A second pass removes what rounding left of n when tangent was nearly parallel to it.
  t -= n * glm::dot(n, t);
  const double len = glm::length(t);
  // A tangent (nearly) parallel to n, zero or non-finite (degenerate UVs) has no usable
  // direction in the tangent plane: keep the normal-only frame.
  const double scale = glm::length(tangent);
  if (!(len > 1e-8 * scale) || !std::isfinite(len)) return from_normal(n);
  LocalFrame f;
  f.n = n;
  f.t = t / len;
  f.b = glm::cross(n, f.t);  // t x (n x t) = n for unit, orthogonal n and t
  return f;
}

}  // namespace prt
