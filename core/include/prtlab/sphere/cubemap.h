#pragma once
// The global direction basis: a cubemap of 6 faces of R x R pixels (N = 6 R^2).
//
// Face order and orientation follow the OpenGL cube map convention:
//   face 0: +X   direction = ( 1, -t, -s)
//   face 1: -X   direction = (-1, -t,  s)
//   face 2: +Y   direction = ( s,  1,  t)
//   face 3: -Y   direction = ( s, -1, -t)
//   face 4: +Z   direction = ( s, -t,  1)
//   face 5: -Z   direction = (-s, -t, -1)
// where s = 2 (x + 0.5) / R - 1 and t = 2 (y + 0.5) / R - 1 for pixel column x and row y
// (row 0 at the top of the face image), before normalisation.
// Pixel index k = face * R * R + y * R + x.
//
// Solid angles are exact (the area of the spherical quadrilateral), not the centre
// approximation: they sum to 4 pi to rounding. Pixel edges are great circles, so a pixel is
// the set of directions that project into its square on the face; it is not the set of
// directions nearest its centre (they differ in slivers near the skewed corners of a face).
// See docs/conventions.md.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "prtlab/base/types.h"

namespace prt {

class CubemapLayout {
 public:
  /// Throws ParameterError unless 1 <= resolution <= 8192.
  explicit CubemapLayout(int resolution);

  int resolution() const { return r_; }
  int pixel_count() const { return 6 * r_ * r_; }  ///< N
  int index(int face, int x, int y) const { return (face * r_ + y) * r_ + x; }

  /// Unit direction through the centre of pixel k.
  Vec3d direction(int k) const;
  /// Exact solid angle of pixel k (steradians).
  double solid_angle(int k) const;
  /// Unit direction through face coordinates (s, t) in [-1, 1]^2.
  static Vec3d face_direction(int face, double s, double t);
  /// Pixel containing direction d (need not be normalised; must be finite and non-zero).
  /// Directions on a face edge or corner get one of the touching pixels (never an index out
  /// of range): ties of the major axis go to X, then Y, then Z, and s = +1 goes to the last
  /// column.
  int pixel_of(const Vec3d& d) const;
  /// Face and continuous face coordinates (s, t) in [-1, 1] of direction d (the face of the
  /// largest |component|, ties as in pixel_of).
  static void face_coords(const Vec3d& d, int& face, double& s, double& t);

  /// Precomputed tables (size N) for loops that visit every pixel.
  std::span<const Vec3d> directions() const { return directions_; }
  std::span<const double> solid_angles() const { return solid_angles_; }

 private:
  int r_;
  std::vector<Vec3d> directions_;
  std::vector<double> solid_angles_;
};

/// RGB radiance per cubemap pixel.
struct Cubemap {
  CubemapLayout layout;
  std::vector<Rgb> radiance;  ///< size N, indexed by pixel k

  explicit Cubemap(int resolution) : layout(resolution), radiance(layout.pixel_count()) {}
  /// Integral of radiance over the sphere per channel: sum_k L_k * solidAngle_k.
  Vec3d total_power() const;
  /// The light vector of DESIGN.md: L_k = radiance_k * solidAngle_k (RGB, float).
  std::vector<Rgb> light_vector() const;
};

}  // namespace prt
