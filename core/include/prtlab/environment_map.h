#pragma once
// Environment lighting: lat-long (equirectangular) HDR images and their area-correct
// resampling onto the cubemap basis.
//
// World convention: +Y is up. A lat-long image of W x H texels covers the sphere with
// column c spanning phi in [2 pi c / W, 2 pi (c+1) / W] and row r spanning the polar angle
// theta (from +Y) in [pi r / H, pi (r+1) / H]; the direction of (theta, phi) is
//   (sin theta sin phi, cos theta, -sin theta cos phi),
// So the image centre (phi = pi, theta = pi/2) looks down +Z, row 0 is the zenith.
// The texel solid angle is exact: (2 pi / W) (cos theta_0 - cos theta_1).
#include <filesystem>
#include <vector>

#include "prtlab/cubemap.h"
#include "prtlab/types.h"

namespace prt {

struct LatLongImage {
  int width = 0;
  int height = 0;
  std::vector<Rgb> texels;  ///< row-major, row 0 at the top (zenith)

  const Rgb& at(int col, int row) const { return texels[static_cast<std::size_t>(row) * width + col]; }
  /// Exact solid angle of a texel in row `row`.
  double texel_solid_angle(int row) const;
  /// Integral of radiance over the sphere per channel (exact texel solid angles).
  Vec3d total_power() const;
};

/// Direction for continuous lat-long coordinates u = phi / 2pi, v = theta / pi in [0,1].
Vec3d latlong_direction(double u, double v);
/// Inverse of latlong_direction.
Vec2d direction_to_latlong(const Vec3d& d);

struct EnvLoadReport {
  std::size_t invalid_texels = 0;  ///< NaN, Inf or negative values replaced by 0
};

/// Load a lat-long EXR (RGB or RGBA, half or float; alpha ignored). NaN, Inf and negative
/// values are replaced by 0 with one warning giving the count. Errors name the file.
LatLongImage load_latlong_exr(const std::filesystem::path& file, EnvLoadReport* report = nullptr);

/// Area-correct resampling: each cubemap pixel receives the radiance of the lat-long texels
/// it covers, weighted by the solid angle of the overlap. Texels are split into sub-texels
/// small relative to a cube pixel, each deposited by its exact solid angle, so the total
/// power sum_k L_k omega_k equals the image's to rounding.
Cubemap resample_to_cubemap(const LatLongImage& image, int resolution);

/// Procedural sun and sky for tests: a sky of radiance `sky` on the upper hemisphere
/// (y > 0) fading to `ground` below, plus a sun of radiance `sun` in a cone of half-angle
/// `sun_radius_rad` around `sun_dir`. Its power has a closed form (procedural_power()).
struct SunSky {
  Vec3d sun_dir{0.3, 0.8, 0.5};
  double sun_radius_rad = 0.05;
  Rgb sun{2000.f, 1900.f, 1700.f};
  Rgb sky{0.6f, 0.75f, 1.0f};
  Rgb ground{0.2f, 0.18f, 0.15f};

  Rgb radiance(const Vec3d& d) const;
  /// Exact integral of radiance over the sphere.
  Vec3d total_power() const;
  LatLongImage to_latlong(int width, int height) const;
  /// Point-sampled (with s x s supersampling per pixel) cubemap of this environment.
  Cubemap to_cubemap(int resolution, int supersample = 4) const;
};

}  // namespace prt
