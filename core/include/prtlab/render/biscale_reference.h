#pragma once
// Brute-force references of the bi-scale model, to validate the bi-scale approximation itself
// (docs/image-error.md derives the error between them and the bi-scale render).
//
// The model: at a pixel x with local frame F (t, b, n), texture coordinates u and view
// direction e (all from the G-buffer), the exitant radiance is direct lighting from the
// environment through the macro visibility and the meso BTF,
//
//   B(x, e) = integral over the hemisphere of F of  b(u, e, w) L_env(w) V(x, w) dw,
//
// with b in the BTF's units (exitant radiance per unit irradiance from w, cosine included).
// The bi-scale render (btf_shading.h) evaluates it as sum_j b(u, e, d_j) L*_j(x) with L*
// from the transfer matrix T at the vertices, interpolated barycentrically.
//
// render_biscale_reference evaluates the integral itself by Monte Carlo, with nothing of the
// bi-scale discretisation:
//   - x is the actual hit point (barycentric combination of the triangle's positions, on the
//     flat triangle), F the G-buffer's frame at x (the vertex frames interpolated and
//     re-orthonormalised exactly as gbuffer.h describes);
//   - V(x, w) is traced with Embree from x for every sample (origin x + eps n_g, n_g the
//     triangle's geometric normal turned to the side of n, eps = ray_offset_relative times the
//     scene's bounding-box diagonal); a w at or below the triangle's plane (w . n_g <= 0) is
//     blocked by the triangle itself and is not traced;
//   - L_env(w) is looked up per sample in a RadianceFunction (a cubemap, a lat-long image or an
//     analytic function: see the helpers below);
//   - b(u, e, w) is evaluated at the continuous direction w: by default from the part's sampled
//     BTF (btf_eval_continuous), or from an analytic BtfFunction given in the options.
// Samples: samples_side^2 per pixel, one jittered sample per stratum of the unit square mapped
// to the cosine-weighted hemisphere (concentric disk, z = sqrt(1 - r^2); pdf cos(theta) / pi),
// so a sample contributes pi * (b / cos) * L * V. The jitter of pixel i comes from a
// SplitMix64 stream seeded by (seed, i): results are deterministic for any thread count.
//
// render_pointwise_transfer is the bi-scale model without vertex interpolation: T is evaluated
// at every pixel's own hit point and frame (same definition as transfer_matrix.h: s x s
// sub-rays per cubemap pixel from x + eps n, pixel centres below the tangent plane lifted into
// the rim cell) and shaded with the sampled BTF, sum_j b(u, e, d_j) L*_j(x). The difference
// from the bi-scale render is exactly the vertex interpolation of L*; its difference from
// render_biscale_reference is the light-direction discretisation (docs/image-error.md).
//
// Both are slow on purpose (thousands of rays per pixel): references, not renderers. TBB over
// rows.
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "prtlab/btf/btf.h"
#include "prtlab/geometry/mesh.h"
#include "prtlab/image/image_io.h"
#include "prtlab/lighting/environment_map.h"
#include "prtlab/render/btf_shading.h"
#include "prtlab/render/gbuffer.h"
#include "prtlab/sphere/cubemap.h"

namespace prt {

/// Environment radiance in a world direction (unit).
using RadianceFunction = std::function<Rgb(const Vec3d& direction)>;

/// Nearest-pixel lookup in a cubemap (piecewise constant: what T sees). Holds a copy.
RadianceFunction cubemap_lookup(const Cubemap& cubemap);
/// Nearest-texel lookup in a lat-long image (environment_map.h convention). Holds a copy.
RadianceFunction latlong_lookup(const LatLongImage& image);
/// A cubemap of a radiance function: every pixel the solid-angle weighted mean over its s x s
/// sub-pixel centres (exact sub-pixel solid angles; s = supersampling).
Cubemap cubemap_from_radiance(int resolution, const RadianceFunction& radiance,
                              int supersampling = 4);

/// An analytic BTF b(part, u, e, w) in the BTF's units; w is a unit local direction with
/// w.z > 0, e the G-buffer's local view direction.
using BtfFunction =
    std::function<Rgb(int part, Vec2 uv, Vec3 view_local, const Vec3d& light_local)>;

/// The sampled BTF at a continuous light direction w (local, unit; b = 0 for w.z <= 0): the
/// texel filter and the view interpolation as Btf::eval_lights, then, over the light samples,
///   b(w) = cos(theta_w) * sum_i omega_i b(d_i) / c_i,
/// the 4 light samples d_i and weights omega_i of btf_view_samples(light_side, w) (the same
/// sphere-measured interpolation the views use) and c_i the cell-mean cosine the stored values
/// carry (btf.h "Units"). Interpolating b / c rather than b keeps the exact cosine (so b -> 0
/// at the horizon) and makes a Lambertian (stored a / pi c_i) exact for every w.
Rgb btf_eval_continuous(const Btf& btf, Vec2 uv, Vec3 view_local, const Vec3d& light_local,
                        TexelFilter filter = TexelFilter::kNearest);

struct BiscaleReferenceOptions {
  int samples_side = 32;  ///< samples_side^2 stratified samples per pixel (even, 2..256)
  std::uint64_t seed = 1;
  TexelFilter filter = TexelFilter::kNearest;
  bool background = true;  ///< misses show L_env(ray direction); else black
  double ray_offset_relative = 1e-4;
  BtfFunction btf;  ///< empty: btf_eval_continuous of the part's BTF
};

struct BiscaleReference {
  RgbImage radiance;  ///< the Monte Carlo estimate of B(x, e)
  /// Per pixel and channel, the estimate's standard error by collapsed strata: horizontally
  /// adjacent strata are paired and Var(mean) = (1/K^2) sum over pairs (f_a - f_b)^2 (Cochran,
  /// Sampling Techniques, ch. 5A). This overestimates the true standard error by the spread of
  /// the stratum means within a pair (a conservative noise level), far less than the plain
  /// sample variance would. 0 for misses.
  RgbImage standard_error;
  int samples_per_pixel = 0;
  std::uint64_t rays_traced = 0;
  double seconds = 0;
};

/// Monte Carlo reference of the bi-scale model (see the file comment). `mesh` is the scene the
/// G-buffer was traced from (it is both receiver and occluder); `part_btfs` gives each part's
/// BTF (needed unless options.btf is set). ParameterError on a part without a BTF or a bad
/// option.
BiscaleReference render_biscale_reference(const GBuffer& gbuffer, const Mesh& mesh,
                                          std::span<const std::shared_ptr<const Btf>> part_btfs,
                                          const RadianceFunction& environment,
                                          const BiscaleReferenceOptions& options = {});

struct PointwiseTransferOptions {
  int supersampling = 2;  ///< s of T
  double ray_offset_relative = 1e-4;
  TexelFilter filter = TexelFilter::kNearest;
  bool background = true;  ///< misses show the cubemap pixel in the ray direction; else black
};

/// The bi-scale model with T evaluated at every pixel's hit point (no vertex interpolation),
/// with the environment's light vector L_k = radiance_k * solidAngle_k and the BTFs' light
/// grids (every BTF's light_count() must be a square S^2; the cells are HemisphereGrid(S)).
RgbImage render_pointwise_transfer(const GBuffer& gbuffer, const Mesh& mesh,
                                   std::span<const std::shared_ptr<const Btf>> part_btfs,
                                   const Cubemap& environment,
                                   const PointwiseTransferOptions& options = {});

}  // namespace prt
