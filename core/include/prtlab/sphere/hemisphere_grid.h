#pragma once
// The local direction basis: an S x S grid over the upper hemisphere (z > 0 in the local
// frame) through the Shirley-Chiu concentric map, which is area preserving, so every cell
// has solid angle 2 pi / S^2 exactly. M = S^2.
//
// Unit square (a, b) in [0,1]^2 -> disk (concentric map) -> hemisphere by
//   r^2 = x^2 + y^2,  z = 1 - r^2,  (x, y) *= sqrt(2 - r^2).
// Cell j = row * S + col covers a in [col/S, (col+1)/S], b in [row/S, (row+1)/S].
// The cell "centre" is the image of the square's centre (a, b) = ((col+.5)/S, (row+.5)/S).
// Orientation: a grows towards +x, b towards +y; the square's centre maps to the zenith
// (0, 0, 1), its edge midpoints to +-x and +-y on the horizon, its corners to the horizon at
// 45 degrees. The same grid serves BTF view samples. See docs/conventions.md.
#include <vector>

#include "prtlab/base/types.h"

namespace prt {

/// Concentric map of the unit square onto the unit disk, and its inverse. With
/// (u, v) = (2a - 1, 2b - 1): if |u| > |v|, r = u and phi = (pi/4) v/u; otherwise r = v and
/// phi = pi/2 - (pi/4) u/v; the disk point is r (cos phi, sin phi). Continuous on the
/// diagonals; the inverse of the origin is the square's centre.
Vec2d square_to_disk_concentric(const Vec2d& ab);
Vec2d disk_to_square_concentric(const Vec2d& xy);
/// Area-preserving unit square -> upper hemisphere, and its inverse (z >= 0 assumed; a
/// direction with z < 0 is mapped as if mirrored to z >= 0).
Vec3d square_to_hemisphere(const Vec2d& ab);
Vec2d hemisphere_to_square(const Vec3d& d);

class HemisphereGrid {
 public:
  /// Throws ParameterError unless 1 <= side <= 4096.
  explicit HemisphereGrid(int side);

  int side() const { return s_; }             ///< S
  int cell_count() const { return s_ * s_; }  ///< M
  /// Local direction of cell j's centre (unit, z > 0).
  Vec3d direction(int j) const { return directions_[j]; }
  const std::vector<Vec3d>& directions() const { return directions_; }
  /// Solid angle of every cell: 2 pi / S^2.
  double cell_solid_angle() const;
  /// Projected solid angle of every cell, the integral of cos(theta) over it (sums to pi);
  /// P_j / cell_solid_angle() is the cell-mean cosine. Computed in closed form (exact up to
  /// rounding): in the concentric map z = 1 - max(u^2, v^2) and the map preserves area.
  std::vector<double> projected_solid_angles() const;
  /// Cell containing local direction d (need not be normalised); -1 when d is below the
  /// horizon (z <= 0) or not finite. Square coordinates on a cell edge or at a = 1, b = 1 are
  /// clamped into [0, S-1].
  int cell_of(const Vec3d& d) const;
  /// Continuous square coordinates of d, for interpolation between cells.
  Vec2d square_coords(const Vec3d& d) const { return hemisphere_to_square(d); }

 private:
  int s_;
  std::vector<Vec3d> directions_;
};

}  // namespace prt
