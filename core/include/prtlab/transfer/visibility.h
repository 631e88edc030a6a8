#pragma once
// Visibility by ray casting (Embree 3): an occlusion scene of a mesh, and the supersampled
// visibility cubemap of a surface point (docs/transfer.md).
//
// The supersampled cubemap splits every pixel of the R x R cubemap (cubemap.h) into s x s
// sub-pixels, so each face is an (sR) x (sR) grid of the same face parameterisation. Sub-ray r
// goes through the centre of a sub-pixel. Sub-rays are ordered pixel-major: sub-ray r belongs
// to global pixel k = r / s^2, and within a pixel the s^2 sub-rays run row by row
// (r % s^2 = sy * s + sx). The visibility value of pixel k is the number of its sub-rays that
// leave the surface point unblocked, an integer count in 0..s^2 (the box filter of the
// supersampled binary visibility, without the 1/s^2 scale).
//
// A sub-ray counts as blocked, without being traced, when its direction is not strictly above
// the tangent plane (dot(d, n) <= 0). The rays that are traced start at p + eps n, where eps is
// a small fraction (default 1e-4) of the scene's bounding-box diagonal, to avoid hitting the
// triangles that contain p.
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <vector>

#include "prtlab/geometry/mesh.h"
#include "prtlab/base/types.h"

namespace prt {

/// Sub-pixel directions of the supersampled cubemap (s R) x (s R) per face, in pixel-major
/// order, with the exact solid angle of every sub-pixel.
class SupersampledCubemap {
 public:
  SupersampledCubemap(int resolution, int supersampling);

  int resolution() const { return r_; }            ///< R
  int supersampling() const { return s_; }         ///< s
  int pixel_count() const { return 6 * r_ * r_; }  ///< N
  int subrays_per_pixel() const { return s_ * s_; }
  std::size_t subray_count() const { return dir_x_.size(); }  ///< N s^2
  /// Global pixel of sub-ray r.
  int pixel_of_subray(std::size_t r) const {
    return static_cast<int>(r / static_cast<std::size_t>(s_ * s_));
  }

  /// Unit direction of sub-ray r (double, from the float tables the tracer uses).
  Vec3d direction(std::size_t r) const { return {dir_x_[r], dir_y_[r], dir_z_[r]}; }
  /// Structure-of-arrays float directions (what the packets are filled from).
  std::span<const float> dir_x() const { return dir_x_; }
  std::span<const float> dir_y() const { return dir_y_; }
  std::span<const float> dir_z() const { return dir_z_; }
  /// Exact solid angle of sub-pixel r (steradians); the s^2 sub-pixels of a pixel sum to its
  /// exact solid angle to rounding, but are not equal to each other.
  std::span<const double> solid_angles() const { return solid_angle_; }
  /// Face coordinates (s, t) in [-1, 1] of the corners of sub-pixel r (for error bounds):
  /// corners are (s0, t0), (s1, t0), (s1, t1), (s0, t1) on face r / (s^2 R^2).
  void subpixel_bounds(std::size_t r, int& face, double& s0, double& s1, double& t0,
                       double& t1) const;

 private:
  int r_, s_;
  std::vector<float> dir_x_, dir_y_, dir_z_;
  std::vector<double> solid_angle_;
};

/// An Embree scene of a mesh's triangles, for occlusion queries. Thread-safe for queries.
/// Owns its Embree device; move-only.
class EmbreeScene {
 public:
  /// Builds the BVH (robust traversal, high build quality). `offset_relative` times the
  /// bounding-box diagonal is the origin offset along the normal in visibility().
  explicit EmbreeScene(const Mesh& mesh, double offset_relative = 1e-4);
  ~EmbreeScene();
  EmbreeScene(EmbreeScene&&) noexcept;
  EmbreeScene& operator=(EmbreeScene&&) noexcept;
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  double bounds_diagonal() const;
  /// Absolute origin offset along the normal used by visibility().
  double ray_offset() const;

  /// True when the open segment origin + t dir, t in (tnear, tfar), hits a triangle.
  bool occluded(const Vec3d& origin, const Vec3d& dir, double tnear = 0.0,
                double tfar = std::numeric_limits<double>::infinity()) const;

  /// Supersampled visibility of the surface point (position, unit normal): counts[k] is the
  /// number of unblocked sub-rays of pixel k (0..s^2); counts.size() must be N. When
  /// `unblocked` is given it receives the ids of the unblocked sub-rays in increasing order.
  /// Returns the number of rays traced (the sub-rays strictly above the tangent plane).
  std::uint64_t visibility(const SupersampledCubemap& dirs, const Vec3d& position,
                           const Vec3d& normal, std::span<std::uint8_t> counts,
                           std::vector<std::uint32_t>* unblocked = nullptr) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace prt
