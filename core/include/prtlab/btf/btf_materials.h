#pragma once
// The meso-structures prtlab turns into BTFs (docs/btf.md): periodic geometry over a unit tile
// with a local BRDF per triangle, and the named materials built from them.
//
// Tile coordinates: x along the texture's u (the local frame's tangent t), y along v (the
// bitangent b), z along the macro normal n; the tile covers [0, 1]^2 in x, y and
// [0, max_height] in z. Geometry must be periodic with period 1 in x and y (the tile repeats
// seamlessly) and must close the tile from below: every vertical line through the tile meets a
// surface, so that a ray coming down from above always hits something.
//
// Named materials (btf_material_names()):
//   lambert  flat Lambertian plane, albedo 0.8 (the default BTF of a scene part)
//   checker  smoothed 4 x 4 checker height field: raised pink squares (glossy, GGX alpha 0.12)
//            over a blue base (rough, alpha 0.45), after Suykens et al. 2003
//   bumps    3 x 3 spherical-cap bumps (orange, semi-gloss) on a matte grey-green base
//   rings    three concentric gold rings (glossy) on a glossy blue base, after Suykens et al.
//   weave    plain weave of red warp and cream weft threads (4 x 4 per tile) over a dark base
//   stucco   periodic fractal noise plaster (single matte material)
//   stone    a measured-looking stone: 5 x 5 grains (warped cellular noise) of three minerals,
//            dark rough crevices between them, worn semi-glossy plateaus, multi-octave relief
//            0.1 high (self-shadowing and masking dominate at grazing angles)
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "prtlab/base/types.h"

namespace prt {

/// Version of the material definitions; part of the BTF cache key (the key also hashes the
/// built geometry and BRDFs, so this only guards against changes the hash cannot see).
inline constexpr std::uint32_t kBtfMaterialsVersion = 1;

/// Local BRDF of the meso-structure: Lambertian diffuse plus a GGX specular lobe with the
/// height-correlated Smith masking term and no Fresnel factor (a constant colour ks). Both
/// lobes conserve energy on their own (single-scattering GGX reflects at most ks), so the
/// directional albedo never exceeds max(kd + ks) when kd + ks <= 1 per channel.
struct LocalBrdf {
  Rgb diffuse{0.8f};       ///< kd: Lambertian albedo (the lobe is kd / pi)
  Rgb specular{0.0f};      ///< ks: scale of the GGX lobe
  float roughness = 0.3f;  ///< GGX alpha (> 0)

  /// f_r(l, v) at a surface of unit normal n for unit l (towards the light) and v (towards the
  /// viewer), without the cosine. 0 when l or v is not strictly above the tangent plane.
  Rgb eval(const Vec3& n, const Vec3& l, const Vec3& v) const;
};

/// Periodic meso-structure geometry over the unit tile (see the file comment).
struct MesoStructure {
  std::string name;
  std::vector<Vec3> positions;
  /// Per-vertex shading normals (unit), interpolated barycentrically at a hit; empty: the
  /// geometric (flat) normal of the triangle is used.
  std::vector<Vec3> normals;
  std::vector<std::uint32_t> indices;       ///< 3 per triangle
  std::vector<std::uint8_t> triangle_brdf;  ///< per triangle, index into brdfs
  std::vector<LocalBrdf> brdfs;
  float max_height = 0.0f;    ///< upper bound of every z
  nlohmann::json parameters;  ///< what built it (shape parameters), for metadata and docs

  std::size_t triangle_count() const { return indices.size() / 3; }
  /// Throws ParameterError on inconsistent arrays, positions outside the tile, a BRDF index out
  /// of range or a non-positive roughness.
  void validate() const;
};

/// Builds a height-field meso-structure: a (grid + 1)^2 vertex lattice over the tile with
/// z = height(x, y) (must be periodic with period 1 and >= 0), two triangles per cell, shading
/// normals from periodic central differences of the lattice heights, and the BRDF of every
/// triangle chosen by brdf_at(x, y, z) at its centroid.
MesoStructure height_field_structure(std::string name, int grid,
                                     const std::function<float(float x, float y)>& height,
                                     const std::function<int(float x, float y, float z)>& brdf_at,
                                     std::vector<LocalBrdf> brdfs);

/// A square box of side `width` (< 1) and `height` centred in the tile on a flat base plane:
/// vertical walls, flat top, geometric normals only. BRDF 0 is the base, 1 the box. The
/// closed-form test case for shadowing: seen from the zenith, a directional light at polar angle
/// theta and azimuth phi shades a base area of width * height * tan(theta) * (|cos phi| +
/// |sin phi|) per tile (while that is below 1 - width in each axis).
MesoStructure box_bump_structure(float width, float height, const LocalBrdf& base,
                                 const LocalBrdf& box);

/// Names of the built-in materials, in a fixed order.
const std::vector<std::string>& btf_material_names();
bool is_btf_material(std::string_view name);
/// One line describing a built-in material (empty for an unknown name).
std::string btf_material_description(std::string_view name);
/// The built-in material `name` with a height-field lattice of `grid` cells per side (ignored by
/// lambert). Throws ParameterError for an unknown name (listing the valid ones) or grid < 8.
MesoStructure make_btf_material(std::string_view name, int grid = 256);

}  // namespace prt
