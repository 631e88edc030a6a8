#pragma once
// A sampled bidirectional texture function b(u, e, d) (docs/btf.md): U x U texels x V view
// directions x M light directions x RGB, float32.
//
// Units: exitant radiance per unit irradiance arriving from the light direction d, measured on
// a plane perpendicular to d, with the cosine at the meso surface included. Light j is a cell
// of the hemisphere grid, not a point: the response is sampled at the cell centre d_j and the
// macro cosine is the cell's mean, c_j = P_j / Omega_j (HemisphereGrid::projected_solid_angles).
// A flat Lambertian of albedo a therefore holds a / pi * c_j for every texel and view, and the
// shading sum of DESIGN.md, B(x, e) = sum_j b(u, e, d_j) L*_j, is the rendering equation's
// quadrature when L*_j is the radiance of light cell j integrated over its solid angle; for
// the Lambertian it is exact (sum_j P_j = pi), where the centre cosine cos(theta_j) would
// overestimate the irradiance by about 2 / S^2 (3.1 % at S = 8).
//
// Sampling:
//   texels  (x, y), x, y in [0, U): texel x covers u in [x/U, (x+1)/U], y covers v likewise;
//           texel index = y * U + x. The tile repeats (wraps) in u and v.
//   views   the cell centres of a view_side x view_side HemisphereGrid (hemisphere_grid.h),
//           V = view_side^2; e points from the surface towards the viewer.
//   lights  the cell centres of a light_side x light_side HemisphereGrid, M = light_side^2 (the
//           scene's local grid S): each value is a point sample at the cell centre direction,
//           not an average over the cell.
//   All directions are in the local frame (t, b, n) = (+u, +v, macro normal).
// Layout: rgb[((texel * V + view) * M + light) * 3 + channel], so that the M light values of
// one (texel, view) pair, the vector b(u, e) of the paper's eq. 3, are contiguous.
//
// View interpolation (btf_view_samples): see the function. Texel lookup: nearest texel with
// wrap-around by default, bilinear (also wrapping) on request.
#include <array>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "prtlab/base/types.h"
#include "prtlab/storage/archive.h"

namespace prt {

/// Archive kind and version of a stored BTF (docs/btf.md lists the sections).
inline constexpr char kBtfArchiveKind[] = "btf";
inline constexpr std::uint32_t kBtfArchiveVersion = 1;

// --- float concentric map (the form the OpenCL shading kernel ports) ----------------------

/// hemisphere_grid.h's square_to_hemisphere in float: unit square (a, b) -> unit direction
/// with z >= 0.
Vec3 square_to_hemisphere_f(Vec2 ab);
/// hemisphere_grid.h's hemisphere_to_square in float; d must be unit with z >= 0.
Vec2 hemisphere_to_square_f(Vec3 d);
/// d clamped to the closed upper hemisphere and normalised: z < 0 is set to 0 (the nearest
/// horizon direction); a direction with no horizontal part and z <= 0 (straight down) becomes
/// +x; a non-finite or zero direction becomes the zenith.
Vec3 clamp_to_hemisphere(Vec3 d);

/// The 4 view samples that interpolate a view direction, and their weights (>= 0, sum 1).
/// Indices may repeat (near the grid's outer edge two or all four coincide).
struct BtfViewSamples {
  std::array<int, 4> view{};
  std::array<float, 4> weight{};
};

/// View interpolation on the sphere (docs/btf.md "View interpolation"). The view direction is
/// clamped to the hemisphere (clamp_to_hemisphere) and mapped to the square; the 2 x 2 sample
/// centres around it in the square give the 4 samples (x0, y0), (x1, y0), (x0, y1), (x1, y1)
/// (clamped at the square's edge, which is the horizon). Their weights are bilinear in
/// (tx, ty), but tx and ty are measured on the sphere, not in the square:
///   tx = |e - P(a_x0, b)| / (|e - P(a_x0, b)| + |e - P(a_x1, b)|),
/// the chordal (angular) distance from e to the two sample columns along the hemisphere curve
/// of constant b through e (P = square_to_hemisphere, a_x = (x + 0.5) / side), and ty likewise
/// along constant a. tx runs from 0 at column x0 to 1 at column x1 and is continuous in e, so
/// the weights are continuous across cell boundaries and reproduce a sample at its centre.
BtfViewSamples btf_view_samples(int view_side, Vec3 view_local);

enum class TexelFilter { kNearest, kBilinear };

/// Whether a BTF whose views all hold the same values is shaded from one view sample.
enum class ViewSkip {
  kDetect,  ///< the constructor compares the views bitwise (the default)
  kNever,   ///< always interpolate 4 view samples: the path the skip is tested and measured against
};

/// The 1 (nearest) or 4 (bilinear) texels and weights for texture coordinates (u, v), wrapping.
struct BtfTexelSamples {
  std::array<int, 4> texel{};
  std::array<float, 4> weight{};
  int count = 1;
};

/// The texel of a U x U tile at (u, v): nearest with wrap-around, u and v in any range.
int btf_texel_at(int resolution, Vec2 uv);
/// The texel samples of a U x U tile at (u, v) (Btf::texel_samples without the data, for any
/// representation sampled like a BTF).
BtfTexelSamples btf_texel_samples(int resolution, Vec2 uv, TexelFilter filter);

class Btf {
 public:
  Btf() = default;
  /// rgb must hold resolution^2 * view_side^2 * light_side^2 * 3 values (ParameterError).
  Btf(std::string material, int resolution, int view_side, int light_side, std::vector<float> rgb,
      nlohmann::json parameters = nlohmann::json::object(), ViewSkip skip = ViewSkip::kDetect);

  const std::string& material() const { return material_; }
  int resolution() const { return resolution_; }  ///< U
  int texel_count() const { return resolution_ * resolution_; }
  int view_side() const { return view_side_; }
  int view_count() const { return view_side_ * view_side_; }  ///< V
  int light_side() const { return light_side_; }
  int light_count() const { return light_side_ * light_side_; }  ///< M
  /// Generation parameters (resolution, supersampling, material shape parameters, ...).
  const nlohmann::json& parameters() const { return parameters_; }

  std::span<const float> data() const { return rgb_; }
  std::size_t value_count() const { return rgb_.size(); }
  std::size_t bytes() const { return rgb_.size() * sizeof(float); }
  /// Index of the red value of (texel, view, light) in data().
  std::size_t offset(int texel, int view, int light) const {
    return ((static_cast<std::size_t>(texel) * view_count() + view) * light_count() + light) * 3;
  }
  Rgb value(int texel, int view, int light) const {
    const float* p = rgb_.data() + offset(texel, view, light);
    return {p[0], p[1], p[2]};
  }
  /// The M RGB values b(texel, view, .) as 3 M floats.
  std::span<const float> light_vector(int texel, int view) const {
    return {rgb_.data() + offset(texel, view, 0), static_cast<std::size_t>(light_count()) * 3};
  }
  /// True when every view of every texel holds bitwise the same 3 M values (a Lambertian without
  /// meso-structure, or view_side 1), unless built with ViewSkip::kNever. Then eval, eval_lights
  /// and shade skip the view interpolation and read view 0 with weight exactly 1 (docs/btf.md
  /// "Diffuse BTFs"): with nearest texels b(u, e, .) is the stored vector itself, where the 4
  /// interpolated samples would carry the rounding of weights that sum to 1 only within 3 ulps.
  bool view_independent() const { return view_independent_; }

  /// Texel index at (u, v): nearest with wrap-around, u and v in any range.
  int texel_at(Vec2 uv) const;
  BtfTexelSamples texel_samples(Vec2 uv, TexelFilter filter) const;
  /// The view samples shading reads at view_local: btf_view_samples, or view 0 with weight 1 (and
  /// 3 zero weights) when view_independent().
  BtfViewSamples view_samples(Vec3 view_local) const;

  /// b(uv, e, d_light): texel filter, then view interpolation.
  Rgb eval(Vec2 uv, Vec3 view_local, int light, TexelFilter filter = TexelFilter::kNearest) const;
  /// The whole vector b(uv, e, .) into out (size M).
  void eval_lights(Vec2 uv, Vec3 view_local, std::span<Rgb> out,
                   TexelFilter filter = TexelFilter::kNearest) const;
  /// Eq. 3 of the central paper: sum_j b(uv, e, d_j) * local_radiance[j] (size M), per channel.
  Rgb shade(Vec2 uv, Vec3 view_local, std::span<const Rgb> local_radiance,
            TexelFilter filter = TexelFilter::kNearest) const;

 private:
  friend ArchiveWriter save_btf(Btf btf);
  std::string material_;
  int resolution_ = 0, view_side_ = 0, light_side_ = 0;
  std::vector<float> rgb_;
  nlohmann::json parameters_ = nlohmann::json::object();
  bool view_independent_ = false;
};

/// Summary statistics for `prtlab btf info` and the tests.
struct BtfStats {
  Rgb min{0.f}, max{0.f}, mean{0.f};
  /// Directional albedo per light j, averaged over texels:
  ///   A_j = (1 / U^2) sum_texels sum_views b(texel, view, j) * P_view / cos(theta_j),
  /// where P_view is the projected solid angle of the view's cell (the integral of cos(theta)
  /// over it; the cells sum to pi): the fraction of the light's flux the tile reflects
  /// (<= 1 without interreflection, up to the quadrature error of V view samples; exact for a
  /// Lambertian).
  std::vector<Rgb> albedo;
  Rgb albedo_mean{0.f};  ///< mean of albedo over the lights
  Rgb albedo_max{0.f};   ///< per-channel maximum of albedo over the lights
  std::size_t non_finite = 0;
};
BtfStats btf_stats(const Btf& btf);

/// A copy of `btf` built with ViewSkip::kNever: the same values, shaded by interpolating 4 view
/// samples even where they are equal.
Btf without_view_skip(const Btf& btf);

/// Archive round trip (kind "btf"; sections "rgb" float32, "view_directions" and
/// "light_directions" float32 x 3; metadata: material, resolution, view_side, light_side,
/// parameters, layout, units). save_btf takes the BTF by value: pass an rvalue to move the data
/// into the archive without a copy. load_btf throws InputError naming the file on any mismatch.
ArchiveWriter save_btf(Btf btf);
Btf load_btf(const ArchiveReader& reader);
void write_btf(const Btf& btf, const std::filesystem::path& file);
Btf read_btf(const std::filesystem::path& file);

}  // namespace prt
