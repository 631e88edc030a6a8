// Material rtt (radiance transfer textures, Sloan et al. 2004): the texture of a Lambertian BTF
// is the clamped-cosine SH convolution (closed-form zonal coefficients); shading SH radiance
// through the texture equals the full BTF's shading of that radiance evaluated at the bins, for
// single lookups and for whole frames on the C++ and OpenCL paths (with the sh_biscale
// transfer); a diffuse BTF gives a view-independent texture. The material conformance suite
// covers the OpenCL evaluation against the C++ one, save/load and the declared error.
#include "rtt/rtt.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "prtlab/btf/btf_generator.h"
#include "prtlab/btf/btf_materials.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/material_error.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/render/frame_renderer.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/sphere/spherical_harmonics.h"
#include "prtlab/transfer/radiance_to_bins.h"
#include "prtlab/transfer/transfer_matrix.h"
#include "support/tiny_frame_scene.h"

namespace prt::rtt {
namespace {

// integral over [0, 1] of z P_l(z): 1/2, 1/3, 0 for odd l > 1, and for even l >= 2
// (-1)^(l/2 + 1) (l - 2)! / (2^l (l/2 - 1)! (l/2 + 1)!).
double z_times_legendre(int l) {
  if (l == 0) return 0.5;
  if (l == 1) return 1.0 / 3.0;
  if (l % 2 == 1) return 0.0;
  const auto fact = [](int k) { return std::tgamma(k + 1.0); };
  const double sign = (l / 2 + 1) % 2 == 0 ? 1.0 : -1.0;
  return sign * fact(l - 2) / (std::pow(2.0, l) * fact(l / 2 - 1) * fact(l / 2 + 1));
}

// A BTF of one texel and one view whose light bins are (albedo / pi) x the cell-mean cosine:
// a Lambertian surface in btf.h's units, built by hand from the grid's closed-form projected
// solid angles (independent of the generator).
Btf lambert_btf(int light_side, float albedo) {
  const HemisphereGrid grid(light_side);
  const std::vector<double> p = grid.projected_solid_angles();
  const double omega = grid.cell_solid_angle();
  std::vector<float> rgb;
  for (int j = 0; j < grid.cell_count(); ++j) {
    const auto v = static_cast<float>(albedo / kPi * p[static_cast<std::size_t>(j)] / omega);
    rgb.insert(rgb.end(), {v, v, v});
  }
  return Btf("lambert", 1, 1, light_side, std::move(rgb));
}

TEST(Rtt, LambertianTextureIsTheClampedCosineZonalConvolution) {
  // rtt_i = (a / pi) integral over H of cos(theta) y_i = (a / pi) 2 pi N_l int_0^1 z P_l(z) for
  // m = 0, and 0 for m != 0 (N_l = sqrt((2 l + 1) / 4 pi)).
  const float albedo = 0.8f;
  for (const int side : {32, 64}) {
    const Btf table = project_btf(lambert_btf(side, albedo), 6);
    double worst = 0;
    for (int l = 0; l < 6; ++l) {
      for (int m = -l; m <= l; ++m) {
        const double expected =
            m != 0
                ? 0.0
                : albedo / kPi * 2 * kPi * std::sqrt((2 * l + 1) / (4 * kPi)) * z_times_legendre(l);
        const Rgb got = table.value(0, 0, sh_index(l, m));
        for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(got[c] - expected));
      }
    }
    SCOPED_TRACE(::testing::Message() << "light side " << side);
    // The bins hold cell means of cos: the product with y_i's cell integral differs from the
    // integral of the product by the in-cell covariance, O(h^2) with h = 1 / side.
    EXPECT_LT(worst, 1e-3);
    RecordProperty("max_abs_error_side_" + std::to_string(side), std::to_string(worst));
  }
  // The first three closed forms: sqrt(pi)/2, sqrt(pi/3), sqrt(5 pi)/8 (times a / pi).
  const Btf t = project_btf(lambert_btf(64, 1.0f), 3);
  EXPECT_NEAR(t.value(0, 0, 0).x, std::sqrt(kPi) / 2 / kPi, 1e-3);
  EXPECT_NEAR(t.value(0, 0, sh_index(1, 0)).x, std::sqrt(kPi / 3) / kPi, 1e-3);
  EXPECT_NEAR(t.value(0, 0, sh_index(2, 0)).x, std::sqrt(5 * kPi) / 8 / kPi, 1e-3);
}

std::shared_ptr<const Btf> generated(const char* material, int light_side) {
  BtfParams p;
  p.resolution = 4;
  p.view_side = 5;
  p.light_side = light_side;
  p.supersampling = 1;
  p.geometry_grid = 32;
  return std::make_shared<const Btf>(generate_btf(make_btf_material(material, 32), p));
}

TEST(Rtt, ShadingShRadianceEqualsTheFullBtfShadingAtTheBins) {
  const int order = 4, n = 16;
  const auto btf = generated("bumps", 6);
  const auto rtt = MaterialRegistry::instance()
                       .create("rtt", {{"order", "4"}})
                       ->compress({btf}, Progress::null());
  EXPECT_EQ(rtt->light_basis(), MaterialLightBasis::spherical_harmonics(order));
  const HemisphereGrid grid(6);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.f, 1.f), t(0.f, 1.f);
  LocalRadiance sh(RadianceBasis::kSphericalHarmonics, n, 1);
  double worst = 0, scale = 0;
  for (int trial = 0; trial < 50; ++trial) {
    for (auto& c : sh.values) c = Rgb(u(rng), u(rng), u(rng));
    const LocalRadiance bins = to_pixel_basis(sh, grid);
    const Vec2 uv{t(rng), t(rng)};
    const Vec3 view = glm::normalize(Vec3{u(rng), u(rng), 0.2f + t(rng)});
    for (const auto filter : {TexelFilter::kNearest, TexelFilter::kBilinear}) {
      const Rgb a = rtt->shade(uv, view, sh.values, filter);
      const Rgb b = btf->shade(uv, view, bins.values, filter);
      for (int c = 0; c < 3; ++c) {
        worst = std::max(worst, static_cast<double>(std::abs(a[c] - b[c])));
        scale = std::max(scale, static_cast<double>(std::abs(b[c])));
      }
    }
  }
  EXPECT_LT(worst, 2e-5 * scale) << "scale " << scale;
}

TEST(Rtt, DiffuseBtfGivesAViewIndependentTexture) {
  const auto btf = generated("lambert", 8);
  ASSERT_TRUE(btf->view_independent());
  const auto m = MaterialRegistry::instance()
                     .create("rtt", {{"order", "5"}})
                     ->compress({btf}, Progress::null());
  const auto& r = dynamic_cast<const RttMaterial&>(*m);
  EXPECT_TRUE(r.table().view_independent());
  // One vector of 25 RGB floats per texel, and 2 n + 2 n FLOPs a pixel (one view sample).
  EXPECT_EQ(m->storage().total_bytes(), std::uint64_t{16} * 25 * 3 * 4);
  EXPECT_DOUBLE_EQ(m->flops_per_pixel(), 4.0 * 25);
  // A view-dependent BTF keeps every view.
  const auto bumps = generated("bumps", 8);
  const auto mb =
      MaterialRegistry::instance().create("rtt", {})->compress({bumps}, Progress::null());
  EXPECT_EQ(mb->storage().total_bytes(), std::uint64_t{16} * 25 * 25 * 3 * 4);
}

TEST(Rtt, ErrorFallsWithTheOrderAndIsTheStoredOne) {
  const auto btf = generated("checker", 8);
  double previous = 2.0;
  for (int order = 1; order <= 8; ++order) {
    const auto m = MaterialRegistry::instance()
                       .create("rtt", {{"order", std::to_string(order)}})
                       ->compress({btf}, Progress::null());
    const double e = m->declared_error_bound();
    EXPECT_NEAR(e, material_error(*m, *btf).relative_l2, 1e-12) << "order " << order;
    EXPECT_LE(e, previous + 1e-9) << "order " << order;
    previous = e;
  }
  // 64 bins, 64 SH functions at order 8: far from exact (the bins are no band-limited basis),
  // but well below the order-1 error.
  EXPECT_LT(previous, 0.5);
}

TEST(Rtt, FramesWithTheTextureEqualFramesWithTheFullBtf) {
  // The whole frame loop: sh_biscale relights into SH of order 4; the rtt material shades it
  // directly, the full material through the bins. Both paths, C++ and OpenCL.
  const testing::TinyFrameScene& tiny = testing::tiny_frame_scene();
  const auto& d = tiny.scene.desc;
  TransferParams tp;
  tp.cubemap_resolution = d.cubemap_resolution;
  tp.local_grid = d.local_grid;
  tp.supersampling = d.supersampling;
  tp.sh_order = 4;
  tp.show_progress = false;
  const TransferResult r = compute_transfer(tiny.scene.mesh, tp);
  const std::shared_ptr<const CompressedTransfer> transfer =
      CompressorRegistry::instance()
          .create("sh_biscale", {{"order", "4"}})
          ->compress({r.transfer, &*r.sh, tiny.layout, tiny.grid}, Progress::null());
  const auto btfs = testing::tiny_scene_btfs(tiny.scene);
  ShadingMaterials with_rtt, with_full;
  with_rtt.part_material = compress_part_materials(btfs, "rtt", {{"order", "4"}});
  with_full.part_material = compress_part_materials(btfs, "full", {});
  CameraOverrides size;
  size.width = 64;
  size.height = 48;
  const Camera cam = scene_camera(tiny.scene, "front", size);
  for (const bool device : {false, true}) {
    ClContext* ctx = device ? default_context() : nullptr;
    if (device && !ctx) continue;
    SCOPED_TRACE(device ? "OpenCL" : "C++");
    const auto frame = [&](const ShadingMaterials& m) {
      FrameRenderer fr(tiny.scene.mesh, m, transfer, ctx);
      fr.set_camera(cam);
      fr.set_environment(tiny.sky);
      fr.render();
      return fr.image();
    };
    const RgbImage a = frame(with_rtt), b = frame(with_full);
    ASSERT_EQ(a.pixels.size(), b.pixels.size());
    double err = 0, peak = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i)
      for (int c = 0; c < 3; ++c) {
        err = std::max(err, static_cast<double>(std::abs(a.pixels[i][c] - b.pixels[i][c])));
        peak = std::max(peak, static_cast<double>(std::abs(b.pixels[i][c])));
      }
    EXPECT_GT(peak, 0);
    EXPECT_LT(err, 1e-5 * peak);
  }
}

}  // namespace
}  // namespace prt::rtt
