// BTF shading: the OpenCL kernels against the C++ reference (nearest and bilinear texels, with
// and without the view cache, a view-independent BTF, background on and off, light and view
// changes); the diffuse skip against interpolating the equal view samples (within the bound of
// docs/btf.md "Diffuse BTFs", bit-identical elsewhere, fewer bytes); and the flat Lambertian
// plane under a constant environment, which must render a * Le (docs/rendering.md "BTF
// shading" derives the tolerance).
#include "prtlab/render/btf_shading.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "prtlab/btf/btf_generator.h"
#include "prtlab/btf/btf_materials.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/geometry/procedural_shapes.h"
#include "prtlab/geometry/scene.h"
#include "prtlab/lighting/environment_map.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt {
namespace {

BtfParams small_btf(int light_side, int resolution = 8, int view_side = 6) {
  BtfParams p;
  p.resolution = resolution;
  p.view_side = view_side;
  p.light_side = light_side;
  p.supersampling = 1;
  p.geometry_grid = 64;
  return p;
}

// The parts' BTFs shaded through the lossless `full` material.
ShadingMaterials full_materials(const std::vector<std::shared_ptr<const Btf>>& btfs) {
  return {compress_part_materials(btfs, "full", {})};
}

// Largest |a - b| over pixels and channels divided by the largest |b| (the image maximum).
double max_error_vs_image_max(const RgbImage& a, const RgbImage& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  double err = 0.0, peak = 0.0;
  for (std::size_t i = 0; i < b.pixels.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      err = std::max(err, static_cast<double>(std::abs(a.pixels[i][c] - b.pixels[i][c])));
      peak = std::max(peak, static_cast<double>(std::abs(b.pixels[i][c])));
    }
  return peak > 0.0 ? err / peak : err;
}

// The tiny scene (sphere over a plane, 2 parts: checker and bumps, M = 16), its G-buffers from
// two views, random non-negative L* and a sun-and-sky background.
struct TinyScene {
  Scene scene =
      load_scene(std::filesystem::path(PRTLAB_SOURCE_DIR) / "scenes/tiny-sphere-plane.toml");
  std::vector<std::shared_ptr<const Btf>> btfs, lambert_btfs;
  ShadingMaterials materials;
  ShadingMaterials with_lambert;  // the plane's BTF replaced by the view-independent lambert
  ShadingMaterials with_lambert_interpolated;  // the same, shaded without the view skip
  GBuffer front, top;
  LocalRadiance radiance, radiance2;
  Cubemap background = SunSky{}.to_cubemap(8, 2);

  TinyScene() {
    const int side = scene.desc.local_grid;
    for (const auto& part : scene.desc.parts)
      btfs.push_back(std::make_shared<const Btf>(
          generate_btf(make_btf_material(part.btf, 64), small_btf(side))));
    lambert_btfs = btfs;
    lambert_btfs[0] =
        std::make_shared<const Btf>(generate_btf(make_btf_material("lambert"), small_btf(side)));
    materials = full_materials(btfs);
    with_lambert = full_materials(lambert_btfs);
    auto interpolated = lambert_btfs;
    interpolated[0] = std::make_shared<const Btf>(without_view_skip(*lambert_btfs[0]));
    with_lambert_interpolated = full_materials(interpolated);
    CameraOverrides size;
    size.width = 96;
    size.height = 72;
    front = render_gbuffer(scene.mesh, scene_camera(scene, "front", size));
    top = render_gbuffer(scene.mesh, scene_camera(scene, "top", size));
    radiance = random_radiance(1);
    radiance2 = random_radiance(2);
  }
  LocalRadiance random_radiance(unsigned seed) const {
    LocalRadiance r(RadianceBasis::kPixel, scene.desc.local_grid * scene.desc.local_grid,
                    scene.mesh.positions.size());
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 2.0f);
    for (auto& v : r.values) v = Rgb(u(rng), u(rng), u(rng));
    return r;
  }
};

const TinyScene& tiny() {
  static const TinyScene s;
  return s;
}

ClContext* context() {
  return default_context();
}

#define PRT_REQUIRE_OPENCL()                                                                \
  do {                                                                                      \
    if (context() == nullptr) GTEST_SKIP() << "no OpenCL device (install pocl-opencl-icd)"; \
  } while (0)

TEST(BtfShading, TinySceneHasHitsMissesAndBothParts) {
  const auto& s = tiny();
  EXPECT_FALSE(s.btfs[0]->view_independent());
  EXPECT_TRUE(s.lambert_btfs[0]->view_independent());
  int parts[2] = {0, 0};
  for (const auto p : s.front.part)
    if (p >= 0) ++parts[p];
  EXPECT_GT(parts[0], 100);
  EXPECT_GT(parts[1], 100);
  EXPECT_GT(s.front.pixel_count() - s.front.hit_count(), 100u);
}

struct KernelCase {
  TexelFilter filter;
  bool cache;
  bool lambert;
  bool background;
};
std::string case_name(const ::testing::TestParamInfo<KernelCase>& info) {
  const auto& c = info.param;
  return std::string(c.filter == TexelFilter::kNearest ? "Nearest" : "Bilinear") +
         (c.cache ? "Cached" : "SinglePass") + (c.lambert ? "Lambert" : "") +
         (c.background ? "" : "NoBackground");
}

void PrintTo(const KernelCase& c, std::ostream* os) {
  *os << (c.filter == TexelFilter::kNearest ? "nearest" : "bilinear")
      << (c.cache ? ", view cache" : ", single pass") << (c.lambert ? ", lambert plane" : "")
      << (c.background ? "" : ", no background");
}

class KernelVsReference : public ::testing::TestWithParam<KernelCase> {};

// The kernel equals the reference within 1e-5 of the image maximum at every pixel, for the
// first frame, after a light change (L* and background) and after a view change.
TEST_P(KernelVsReference, Within1e5OfImageMax) {
  PRT_REQUIRE_OPENCL();
  const auto& s = tiny();
  const KernelCase c = GetParam();
  ShadingOptions o;
  o.filter = c.filter;
  o.cache_view_vectors = c.cache;
  o.background = c.background;
  const ShadingMaterials& mats = c.lambert ? s.with_lambert : s.materials;
  DeviceBtfShader shader(*context(), s.scene.mesh, mats, &s.background, o);

  shader.set_gbuffer(s.front);
  shader.set_radiance(s.radiance);
  shader.shade();
  const RgbImage ref1 =
      shade_frame_reference(s.front, s.scene.mesh, mats, s.radiance, &s.background, o);
  const double e1 = max_error_vs_image_max(shader.read_image(), ref1);
  EXPECT_LE(e1, 1e-5) << "first frame";

  // Light change: new L*, a brighter background; the view cache must be reused, not stale.
  Cubemap bg2 = s.background;
  for (auto& v : bg2.radiance) v *= 3.0f;
  shader.set_radiance(s.radiance2);
  shader.set_background(&bg2);
  shader.shade();
  EXPECT_EQ(shader.last_view_cache_ms(), 0.0);
  const RgbImage ref2 = shade_frame_reference(s.front, s.scene.mesh, mats, s.radiance2, &bg2, o);
  EXPECT_LE(max_error_vs_image_max(shader.read_image(), ref2), 1e-5) << "after a light change";

  // View change.
  shader.set_gbuffer(s.top);
  shader.shade();
  const RgbImage ref3 = shade_frame_reference(s.top, s.scene.mesh, mats, s.radiance2, &bg2, o);
  EXPECT_LE(max_error_vs_image_max(shader.read_image(), ref3), 1e-5) << "after a view change";

  // Misses: the background pixel containing the ray direction, or black.
  const std::size_t i = [&] {
    for (std::size_t k = 0; k < s.top.pixel_count(); ++k)
      if (s.top.triangle[k] < 0) return k;
    return std::size_t{0};
  }();
  const Vec3d d(s.top.direction[4 * i], s.top.direction[4 * i + 1], s.top.direction[4 * i + 2]);
  const Rgb expected = c.background ? bg2.radiance[bg2.layout.pixel_of(d)] : Rgb(0.0f);
  EXPECT_EQ(ref3.pixels[i], expected);
}

INSTANTIATE_TEST_SUITE_P(Cases, KernelVsReference,
                         ::testing::Values(KernelCase{TexelFilter::kNearest, true, false, true},
                                           KernelCase{TexelFilter::kNearest, false, false, true},
                                           KernelCase{TexelFilter::kBilinear, true, false, true},
                                           KernelCase{TexelFilter::kBilinear, false, false, true},
                                           KernelCase{TexelFilter::kNearest, true, true, true},
                                           KernelCase{TexelFilter::kBilinear, false, true, false}),
                         case_name);

// Both kernels give the same image (they differ only in where b(u, e) is summed).
TEST(BtfShading, CachedAndSinglePassAgree) {
  PRT_REQUIRE_OPENCL();
  const auto& s = tiny();
  ShadingOptions cached, single;
  single.cache_view_vectors = false;
  DeviceBtfShader a(*context(), s.scene.mesh, s.materials, &s.background, cached);
  DeviceBtfShader b(*context(), s.scene.mesh, s.materials, &s.background, single);
  for (auto* sh : {&a, &b}) {
    sh->set_gbuffer(s.front);
    sh->set_radiance(s.radiance);
    sh->shade();
  }
  EXPECT_GT(a.last_view_cache_ms(), 0.0);
  EXPECT_LE(max_error_vs_image_max(a.read_image(), b.read_image()), 1e-6);
  EXPECT_EQ(a.hit_pixels(), s.front.hit_count());
  // Bytes: nearest, 2 view-dependent parts: 4 vectors of 3M floats + 3 vertices per hit pixel.
  const std::uint64_t vec = 16 * 3 * 4;
  EXPECT_EQ(a.bytes_read_per_frame(), s.front.hit_count() * (4 + 3) * vec);
  EXPECT_EQ(a.bytes_per_pass().cached_shade, s.front.hit_count() * (1 + 3) * vec);
}

// The first pass after a new G-buffer shades the hits while it builds the cache
// (btf_view_cache_shade); the next reads the cache back (btf_shade_cached). Same values, same
// order: the two images are bit-identical, for both filters and an odd light grid's tail.
TEST(BtfShading, ViewCacheBuildingPassEqualsTheCachedPassBitwise) {
  PRT_REQUIRE_OPENCL();
  const auto& s = tiny();
  for (const auto filter : {TexelFilter::kNearest, TexelFilter::kBilinear}) {
    ShadingOptions o;
    o.filter = filter;
    DeviceBtfShader sh(*context(), s.scene.mesh, s.materials, &s.background, o);
    sh.set_gbuffer(s.front);
    sh.set_radiance(s.radiance);
    sh.shade();
    ASSERT_GT(sh.last_view_cache_ms(), 0.0);
    const RgbImage first = sh.read_image();
    sh.shade();
    EXPECT_EQ(sh.last_view_cache_ms(), 0.0);
    const RgbImage second = sh.read_image();
    ASSERT_EQ(first.pixels.size(), second.pixels.size());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < first.pixels.size(); ++i)
      differ += std::memcmp(&first.pixels[i], &second.pixels[i], sizeof(Rgb)) != 0 ? 1 : 0;
    EXPECT_EQ(differ, 0u) << (filter == TexelFilter::kNearest ? "nearest" : "bilinear");
  }
}

// An odd light grid (S = 5, M = 25: 75 floats per vector, 72 in 12-float chunks and a tail of
// 3 done one at a time) through both kernels and both filters.
TEST(BtfShading, OddLightGridUsesTheScalarTail) {
  PRT_REQUIRE_OPENCL();
  const auto& s = tiny();
  std::vector<std::shared_ptr<const Btf>> btfs;
  for (const auto& part : s.scene.desc.parts)
    btfs.push_back(std::make_shared<const Btf>(
        generate_btf(make_btf_material(part.btf, 64), small_btf(5, 4, 4))));
  const ShadingMaterials mats = full_materials(btfs);
  LocalRadiance radiance(RadianceBasis::kPixel, 25, s.scene.mesh.positions.size());
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 2.0f);
  for (auto& v : radiance.values) v = Rgb(u(rng), u(rng), u(rng));
  for (const auto filter : {TexelFilter::kNearest, TexelFilter::kBilinear}) {
    for (const bool cache : {true, false}) {
      ShadingOptions o;
      o.filter = filter;
      o.cache_view_vectors = cache;
      DeviceBtfShader shader(*context(), s.scene.mesh, mats, &s.background, o);
      shader.set_gbuffer(s.front);
      shader.set_radiance(radiance);
      shader.shade();
      const RgbImage ref =
          shade_frame_reference(s.front, s.scene.mesh, mats, radiance, &s.background, o);
      EXPECT_LE(max_error_vs_image_max(shader.read_image(), ref), 1e-5)
          << (filter == TexelFilter::kNearest ? "nearest" : "bilinear")
          << (cache ? ", view cache" : ", single pass");
    }
  }
}

// ---- diffuse skip ------------------------------------------------------------------------------
//
// The plane's lambert BTF shaded with the skip (one view, weight 1) and without it (4 equal view
// samples interpolated): misses and the sphere's view-dependent pixels are bit-identical, the
// plane's within the bounds of docs/btf.md "Diffuse BTFs" (L* and the BTF are non-negative, so
// the bound's sum of |terms| is the pixel's value): C++ 7 u nearest, 24 u bilinear; OpenCL
// (7 or 24) u + 2 (M / 4 + 3) u, the interpolation before the dot product plus the rounding of
// two dot products of M / 4 float4 steps and the lane sum (M = 16 here: 21 u and 38 u). The
// tests add 1 u: they scale by the computed pixel, not the exact sum.
struct SkipComparison {
  double worst_rel = 0;          // over the plane's pixels and channels, in units of its value
  std::size_t plane_pixels = 0;  // pixels of the lambert part
  std::size_t unequal_elsewhere = 0;
};

SkipComparison compare_skip(const GBuffer& g, const RgbImage& skipped,
                            const RgbImage& interpolated) {
  SkipComparison r;
  for (std::size_t i = 0; i < g.pixel_count(); ++i) {
    if (g.part[i] != 0) {
      r.unequal_elsewhere += skipped.pixels[i] != interpolated.pixels[i];
      continue;
    }
    ++r.plane_pixels;
    for (int c = 0; c < 3; ++c) {
      const double a = skipped.pixels[i][c], b = interpolated.pixels[i][c];
      if (a != b) r.worst_rel = std::max(r.worst_rel, std::abs(a - b) / std::abs(a));
    }
  }
  return r;
}

constexpr double kUlp = 0x1p-24;

TEST(BtfShading, DiffuseSkipMatchesInterpolationWithinTheDerivedBoundCpp) {
  const auto& s = tiny();
  ASSERT_TRUE(s.lambert_btfs[0]->view_independent());
  for (const auto filter : {TexelFilter::kNearest, TexelFilter::kBilinear}) {
    ShadingOptions o;
    o.filter = filter;
    for (const GBuffer* g : {&s.front, &s.top}) {
      const RgbImage a =
          shade_frame_reference(*g, s.scene.mesh, s.with_lambert, s.radiance, &s.background, o);
      const RgbImage b = shade_frame_reference(*g, s.scene.mesh, s.with_lambert_interpolated,
                                               s.radiance, &s.background, o);
      const SkipComparison r = compare_skip(*g, a, b);
      const double bound = (filter == TexelFilter::kNearest ? 8 : 25) * kUlp;
      EXPECT_GT(r.plane_pixels, 100u);
      EXPECT_EQ(r.unequal_elsewhere, 0u);
      EXPECT_LE(r.worst_rel, bound) << "worst " << r.worst_rel / kUlp << " u";
    }
  }
}

TEST(BtfShading, DiffuseSkipMatchesInterpolationWithinTheDerivedBoundOpenCl) {
  PRT_REQUIRE_OPENCL();
  const auto& s = tiny();
  const int m = s.radiance.dim;
  const std::uint64_t vector = static_cast<std::uint64_t>(m) * 12;
  for (const auto filter : {TexelFilter::kNearest, TexelFilter::kBilinear}) {
    for (const bool cache : {true, false}) {
      SCOPED_TRACE(::testing::Message()
                   << (filter == TexelFilter::kNearest ? "nearest" : "bilinear")
                   << (cache ? ", view cache" : ", single pass"));
      ShadingOptions o;
      o.filter = filter;
      o.cache_view_vectors = cache;
      DeviceBtfShader skip(*context(), s.scene.mesh, s.with_lambert, &s.background, o);
      DeviceBtfShader interp(*context(), s.scene.mesh, s.with_lambert_interpolated, &s.background,
                             o);
      for (auto* sh : {&skip, &interp}) {
        sh->set_gbuffer(s.front);
        sh->set_radiance(s.radiance);
        sh->shade();
      }
      const SkipComparison r = compare_skip(s.front, skip.read_image(), interp.read_image());
      const double bound = ((filter == TexelFilter::kNearest ? 8 : 25) + 2 * (m / 4 + 3)) * kUlp;
      EXPECT_GT(r.plane_pixels, 100u);
      EXPECT_EQ(r.unequal_elsewhere, 0u);
      EXPECT_LE(r.worst_rel, bound) << "worst " << r.worst_rel / kUlp << " u";

      // The skip reads one view vector per texel of a plane pixel instead of 4, and the plane's
      // BTF is on the device with its one view.
      const std::uint64_t texels = filter == TexelFilter::kBilinear ? 4 : 1;
      EXPECT_EQ(interp.bytes_read_per_frame() - skip.bytes_read_per_frame(),
                r.plane_pixels * 3 * texels * vector);
      const Btf& plane = *s.lambert_btfs[0];
      EXPECT_EQ(
          interp.device_bytes() - skip.device_bytes(),
          static_cast<std::uint64_t>(plane.texel_count()) * (plane.view_count() - 1) * vector);
    }
  }
}

// When every part is a view-independent BTF looked up at the nearest texel, the cached vector
// would be the stored one: the shader runs the single-pass kernel instead (no cache kernel, no
// cache memory), with the single-pass image bit for bit. With bilinear texels, with a
// view-dependent part, or without the skip, the cache is used.
TEST(BtfShading, ViewCacheIsSkippedWhenNoPartGainsFromIt) {
  PRT_REQUIRE_OPENCL();
  const auto& s = tiny();
  const auto lambert = s.lambert_btfs[0];
  const ShadingMaterials all_lambert = full_materials({lambert, lambert});
  const auto interpolated = std::make_shared<const Btf>(without_view_skip(*lambert));
  const ShadingMaterials all_interpolated = full_materials({interpolated, interpolated});
  auto uses_cache = [&](const ShadingMaterials& m, TexelFilter filter) {
    ShadingOptions o;
    o.filter = filter;
    return DeviceBtfShader(*context(), s.scene.mesh, m, &s.background, o).uses_view_cache();
  };
  EXPECT_FALSE(uses_cache(all_lambert, TexelFilter::kNearest));
  EXPECT_TRUE(uses_cache(all_lambert, TexelFilter::kBilinear));
  EXPECT_TRUE(uses_cache(s.with_lambert, TexelFilter::kNearest));
  EXPECT_TRUE(uses_cache(all_interpolated, TexelFilter::kNearest));
  EXPECT_TRUE(uses_cache(s.materials, TexelFilter::kNearest));

  ShadingOptions cached, single;
  single.cache_view_vectors = false;
  DeviceBtfShader a(*context(), s.scene.mesh, all_lambert, &s.background, cached);
  DeviceBtfShader b(*context(), s.scene.mesh, all_lambert, &s.background, single);
  EXPECT_FALSE(b.uses_view_cache());
  for (const GBuffer* g : {&s.front, &s.top}) {
    for (auto* sh : {&a, &b}) {
      sh->set_gbuffer(*g);
      sh->set_radiance(s.radiance);
      sh->shade();
    }
    EXPECT_EQ(a.last_view_cache_ms(), 0.0);
    const RgbImage ia = a.read_image(), ib = b.read_image();
    EXPECT_EQ(ia.pixels, ib.pixels);
    EXPECT_EQ(a.device_bytes(), b.device_bytes());
    ShadingOptions o;
    const RgbImage ref =
        shade_frame_reference(*g, s.scene.mesh, all_lambert, s.radiance, &s.background, o);
    EXPECT_LE(max_error_vs_image_max(ia, ref), 1e-5);
  }
}

// A light change shades the hit pixels only: the misses keep what the view pass wrote, and a
// new background (same layout, other values) between two light changes still reaches them. The
// image equals a fresh shader's with that background, bit for bit.
TEST(BtfShading, LightChangeKeepsTheMissesAndABackgroundChangeReachesThem) {
  PRT_REQUIRE_OPENCL();
  const auto& s = tiny();
  Cubemap brighter = s.background;
  for (Rgb& c : brighter.radiance) c = c * 2.0f + Rgb(0.25f);
  DeviceBtfShader sh(*context(), s.scene.mesh, s.materials, &s.background);
  ASSERT_TRUE(sh.uses_view_cache());
  sh.set_gbuffer(s.front);
  sh.set_radiance(s.radiance);
  sh.shade();  // view pass: cache, hits, misses
  sh.shade();  // light change: hits only
  DeviceBtfShader fresh(*context(), s.scene.mesh, s.materials, &s.background);
  fresh.set_gbuffer(s.front);
  fresh.set_radiance(s.radiance);
  fresh.shade();
  EXPECT_EQ(sh.read_image().pixels, fresh.read_image().pixels);

  sh.set_background(&brighter);
  sh.shade();  // still a light change (the cache holds), the misses rewritten
  EXPECT_EQ(sh.last_view_cache_ms(), 0.0);
  DeviceBtfShader fresh_brighter(*context(), s.scene.mesh, s.materials, &brighter);
  fresh_brighter.set_gbuffer(s.front);
  fresh_brighter.set_radiance(s.radiance);
  fresh_brighter.shade();
  const RgbImage got = sh.read_image(), want = fresh_brighter.read_image();
  EXPECT_EQ(got.pixels, want.pixels);
  std::size_t misses_changed = 0;
  const RgbImage before = fresh.read_image();
  for (std::size_t i = 0; i < got.pixels.size(); ++i)
    misses_changed += s.front.triangle[i] < 0 && !(got.pixels[i] == before.pixels[i]) ? 1 : 0;
  EXPECT_GT(misses_changed, 0u);
}

TEST(BtfShading, RejectsMismatchedMaterialsAndRadiance) {
  const auto& s = tiny();
  ShadingMaterials one;
  one.part_material.push_back(s.materials.part_material[0]);
  EXPECT_THROW(validate_materials(one, s.scene.mesh), ParameterError);  // 2 parts
  ShadingMaterials missing = s.materials;
  missing.part_material[1] = nullptr;
  EXPECT_THROW(validate_materials(missing, s.scene.mesh), ParameterError);
  EXPECT_EQ(validate_materials(s.materials, s.scene.mesh), MaterialLightBasis::pixel_bins(4));
  // Parts whose materials take light in different bases (M = 16 and M = 25) cannot share L*.
  ShadingMaterials mixed = s.materials;
  mixed.part_material[1] = compress_material(
      "full", {},
      std::make_shared<const Btf>(generate_btf(make_btf_material("lambert"), small_btf(5, 4, 4))));
  EXPECT_THROW(validate_materials(mixed, s.scene.mesh), ParameterError);
  LocalRadiance m64(RadianceBasis::kPixel, 64, s.scene.mesh.positions.size());
  EXPECT_THROW(shade_frame_reference(s.front, s.scene.mesh, s.materials, m64, nullptr),
               ParameterError);  // M
  LocalRadiance wrong(RadianceBasis::kPixel, 16, 3);
  EXPECT_THROW(shade_frame_reference(s.front, s.scene.mesh, s.materials, wrong, nullptr),
               ParameterError);
  LocalRadiance sh(RadianceBasis::kSphericalHarmonics, 16, s.scene.mesh.positions.size());
  EXPECT_THROW(shade_frame_reference(s.front, s.scene.mesh, s.materials, sh, nullptr),
               ParameterError);
}

// ---- flat Lambertian plane -------------------------------------------------------------------
//
// A plane under a constant environment Le with nothing above it; its BTF is a flat Lambertian
// of albedo a, stored as b_j = (a / pi) c_j with c_j = P_j / Omega_j the cell-mean cosine of
// light cell j (btf.h). T bins every pixel of the upper hemisphere into the concentric cell
// containing it, so L*_j = Le Omega~_j, where Omega~_j is the solid angle of the whole cubemap
// pixels whose centres fall in cell j, and
//   B = (a / pi) Le sum_j c_j Omega~_j = a Le (1 + (1/pi) sum_j c_j (Omega~_j - Omega_j)),
// since sum_j c_j Omega_j = sum_j P_j = pi. What remains is the binning: pixels straddling a
// cell border move solid angle between neighbouring cells, weighted by the difference of their
// mean cosines; the signed moves largely cancel (measured 0.14 % at S = 8, 0.01 % at S = 16;
// docs/rendering.md). With the centre cosine cos(theta_j) instead of c_j the image would be
// a Le (1 + 2 / S^2): 12.5 % too bright at S = 4, 3.1 % at S = 8.
struct PlaneResult {
  double worst_rel = 0;  // max over hit pixels and channels of |B / (a Le) - expected|
  double mean_ratio = 0;
  std::size_t hits = 0;
};

PlaneResult render_lambert_plane(int side, bool device, double expected_ratio) {
  Mesh plane = make_plane(2.0, 2.0, 4);
  TransferParams tp;
  tp.cubemap_resolution = 32;
  tp.local_grid = side;
  tp.supersampling = 2;
  tp.show_progress = false;
  const TransferMatrix t = compute_transfer(plane, tp).transfer;
  const Rgb le(1.5f, 0.75f, 3.0f);
  Cubemap env(32);
  std::fill(env.radiance.begin(), env.radiance.end(), le);
  const LocalRadiance lstar = relight_exact(t, env.light_vector());

  const Rgb albedo(0.8f, 0.5f, 0.2f);
  const MesoStructure flat = height_field_structure(
      "flat", 8, [](float, float) { return 0.0f; }, [](float, float, float) { return 0; },
      {LocalBrdf{albedo, Rgb(0.0f), 0.3f}});
  const ShadingMaterials mats =
      full_materials({std::make_shared<const Btf>(generate_btf(flat, small_btf(side, 4, 4)))});

  Camera cam;
  cam.eye = {0.3, 1.2, 1.4};
  cam.target = {0, 0, 0};
  cam.width = 64;
  cam.height = 48;
  const GBuffer g = render_gbuffer(plane, cam);
  RgbImage image;
  if (device) {
    DeviceBtfShader shader(*context(), plane, mats, &env);
    shader.set_gbuffer(g);
    shader.set_radiance(lstar);
    shader.shade();
    image = shader.read_image();
  } else {
    image = shade_frame_reference(g, plane, mats, lstar, &env);
  }
  PlaneResult r;
  double sum = 0;
  for (std::size_t i = 0; i < g.pixel_count(); ++i) {
    if (g.triangle[i] < 0) continue;
    ++r.hits;
    for (int c = 0; c < 3; ++c) {
      const double ratio = image.pixels[i][c] / (albedo[c] * le[c]);
      sum += ratio;
      r.worst_rel = std::max(r.worst_rel, std::abs(ratio - expected_ratio));
    }
  }
  r.mean_ratio = sum / (3.0 * static_cast<double>(r.hits));
  return r;
}

// The paper's local grid, S = 8, both paths.
TEST(BtfShading, FlatLambertianRendersAlbedoTimesRadianceWithin1Percent) {
  for (const bool device : {false, true}) {
    if (device && !context()) continue;
    const PlaneResult r = render_lambert_plane(8, device, 1.0);
    EXPECT_GT(r.hits, 1000u);
    EXPECT_LE(r.worst_rel, 0.01) << (device ? "device" : "C++")
                                 << ": mean B / (a Le) = " << r.mean_ratio;
  }
}

// No 2 / S^2 bias at any grid: within 0.3 % at S = 4, 8 and 16 (the centre cosine would be
// 12.5 %, 3.1 % and 0.8 % too bright).
TEST(BtfShading, FlatLambertianHasNoGridBias) {
  for (const int side : {4, 8, 16}) {
    const PlaneResult r = render_lambert_plane(side, false, 1.0);
    EXPECT_LE(r.worst_rel, 0.003) << "S = " << side << ": mean B / (a Le) = " << r.mean_ratio;
  }
}

}  // namespace
}  // namespace prt
