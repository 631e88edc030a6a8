#pragma once
// Orthonormal local frame (tangent t, bitangent b, normal n), right-handed: t x b = n.
// Local coordinates of a world direction d are (d.t, d.b, d.n).
#include "prtlab/base/types.h"

namespace prt {

struct LocalFrame {
  Vec3d t{1, 0, 0};
  Vec3d b{0, 1, 0};
  Vec3d n{0, 0, 1};

  Vec3d to_local(const Vec3d& d) const { return {glm::dot(d, t), glm::dot(d, b), glm::dot(d, n)}; }
  Vec3d to_world(const Vec3d& l) const { return l.x * t + l.y * b + l.z * n; }

  /// A stable frame from the normal alone (Duff et al. 2017, "Building an orthonormal basis,
  /// revisited"): continuous except across the plane n.z = 0, no branch on a threshold.
  /// n is normalised first (must be finite and non-zero). n = +z gives t = +x, b = +y;
  /// n = -z gives t = +x, b = -y.
  static LocalFrame from_normal(const Vec3d& n);
  /// A frame whose tangent follows `tangent` projected into the normal's plane
  /// (Gram-Schmidt), b = n x t; falls back to from_normal when the projection is degenerate
  /// (shorter than 1e-8 |tangent|, zero or not finite).
  static LocalFrame from_normal_tangent(const Vec3d& n, const Vec3d& tangent);
  /// The same for an n already of unit length (not normalised again; the G-buffer's per-pixel
  /// frames): the normal-only frame is built only when the tangent degenerates.
  static LocalFrame from_unit_normal_tangent(const Vec3d& n, const Vec3d& tangent);
};

}  // namespace prt
