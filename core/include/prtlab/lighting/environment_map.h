#pragma once
// Environment lighting: lat-long (equirectangular) HDR images and their area-correct
// resampling onto the cubemap basis.
//
// World convention: +Y is up. A lat-long image of W x H texels covers the sphere with
// column c spanning phi in [2 pi c / W, 2 pi (c+1) / W] and row r spanning the polar angle
// theta (from +Y) in [pi r / H, pi (r+1) / H]; the direction of (theta, phi) is
//   (sin theta sin phi, cos theta, -sin theta cos phi),
// So the image centre (phi = pi, theta = pi/2) looks down +Z, row 0 is the zenith, the left
// and right image edges (phi = 0 = 2 pi) look down -Z, and phi = pi/2 (a quarter of the
// way across) looks down +X.
// The texel solid angle is exact: (2 pi / W) (cos theta_0 - cos theta_1).
#include <filesystem>
#include <vector>

#include "prtlab/base/types.h"
#include "prtlab/sphere/cubemap.h"

namespace prt {

struct LatLongImage {
  int width = 0;
  int height = 0;
  std::vector<Rgb> texels;  ///< row-major, row 0 at the top (zenith)

  const Rgb& at(int col, int row) const {
    return texels[static_cast<std::size_t>(row) * width + col];
  }
  /// Exact solid angle of a texel in row `row`.
  double texel_solid_angle(int row) const;
  /// Integral of radiance over the sphere per channel (exact texel solid angles).
  Vec3d total_power() const;
};

/// Direction for continuous lat-long coordinates u = phi / 2pi, v = theta / pi in [0,1].
Vec3d latlong_direction(double u, double v);
/// Inverse of latlong_direction: (u, v) with u in [0, 1), v in [0, 1]. d need not be
/// normalised (must be non-zero). At the poles u is 0.
Vec2d direction_to_latlong(const Vec3d& d);

struct EnvLoadReport {
  std::size_t invalid_texels = 0;  ///< texels with a NaN, Inf or negative channel, set to 0
  float max_radiance = 0;          ///< the largest channel value kept
  bool aspect_2_to_1 = true;       ///< width == 2 x height, as a lat-long map is
};

/// Radiance above this warns ("radiance-range"): a float relight sums up to 6 R^2 products and
/// error norms square them, which leaves float's range near 1e19.
inline constexpr float kRadianceWarnLimit = 1e15f;
/// Radiance above this is refused: a relight over a 64 x 64 cubemap (24,576 pixels) of such
/// values overflows float to +Inf.
inline constexpr float kRadianceLimit = 1e30f;

/// Load a lat-long EXR (RGB or RGBA, or luminance-only Y; half or float; scanline or tiled;
/// alpha ignored). NaN, Inf and negative channel values are replaced by 0 with one warning
/// giving the number of texels affected. A map that is not 2:1 warns ("latlong-aspect"): it is
/// stretched onto the sphere. Errors (missing file, not an EXR, truncated, no colour channels,
/// radiance above kRadianceLimit) are InputErrors naming the file.
LatLongImage load_latlong_exr(const std::filesystem::path& file, EnvLoadReport* report = nullptr);

/// Area-correct resampling: each cubemap pixel receives the radiance of the lat-long texels
/// it covers, weighted by the solid angle of the overlap, divided by the pixel's solid angle.
/// The overlaps are computed exactly (closed-form integrals in the equal-area (phi, cos theta)
/// plane, where a cube pixel's edges are curves z(phi) with a closed-form primitive), so both
///   - the total power sum_k L_k omega_k equals the image's total_power() to rounding, and
///   - a constant image resamples to the same constant in every pixel, to rounding,
/// hold for any image size and any cubemap resolution (pixels smaller or larger than texels).
/// Parallel over pixels (TBB); deterministic.
Cubemap resample_to_cubemap(const LatLongImage& image, int resolution);

/// Procedural sun and sky for tests: a sky of radiance `sky` on the upper hemisphere (y > 0)
/// and `ground` on the lower one (a sharp horizon), plus a sun of radiance `sun` (replacing
/// sky or ground) in the cone of half-angle `sun_radius_rad` around `sun_dir` (need not be
/// normalised). The sun may lie anywhere, including straddling the horizon.
struct SunSky {
  Vec3d sun_dir{0.3, 0.8, 0.5};
  double sun_radius_rad = 0.05;
  Rgb sun{2000.f, 1900.f, 1700.f};
  Rgb sky{0.6f, 0.75f, 1.0f};
  Rgb ground{0.2f, 0.18f, 0.15f};

  Rgb radiance(const Vec3d& d) const;
  /// Exact integral of radiance over the sphere (closed form): 2 pi (sky + ground) plus, for
  /// the sun cone, (sun - sky) times its solid angle above the horizon and (sun - ground)
  /// times its solid angle below it (a cap cut by a great circle has a closed-form area).
  Vec3d total_power() const;
  /// Lat-long image whose texels are the radiance averaged over s x s sub-texels, each
  /// weighted by its exact solid angle (so the sun's edge is anti-aliased).
  LatLongImage to_latlong(int width, int height, int supersample = 4) const;
  /// Point-sampled (with s x s supersampling per pixel, each sample weighted by its exact
  /// solid angle) cubemap of this environment.
  Cubemap to_cubemap(int resolution, int supersample = 4) const;
};

/// Solid angle of the part of a spherical cap (angular radius `radius` in (0, pi/2], centre c)
/// on the positive side of a plane through the origin with unit normal n, i.e. of
/// {d : angle(d, c) <= radius, d . n >= 0}, where `elevation` = asin(c . n) in [-pi/2, pi/2].
double cap_area_above_plane(double radius, double elevation);

}  // namespace prt
