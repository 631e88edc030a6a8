// BTF generation: the flat Lambertian's closed form, shadows of a box bump against the closed
// form, masking by bumps at grazing views, rays wrapping around the periodic tile, energy
// conservation of every material, interreflection and determinism.
#include "prtlab/btf/btf_generator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/btf/btf.h"
#include "prtlab/btf/btf_materials.h"
#include "prtlab/sphere/hemisphere_grid.h"

namespace prt {
namespace {

BtfParams tiny(int u = 8, int views = 4, int lights = 4) {
  BtfParams p;
  p.resolution = u;
  p.view_side = views;
  p.light_side = lights;
  return p;
}

// The macro cosine is the cell mean P_j / Omega_j (btf.h "Units"), so a Lambertian's values sum
// to the exact irradiance: sum_j b_j Omega_j = albedo / pi * sum_j P_j = albedo.
TEST(BtfGenerator, LambertIsAlbedoOverPiTimesCellMeanCosine) {
  const Btf b = generate_btf(make_btf_material("lambert"), tiny());
  const HemisphereGrid lights(4);
  const std::vector<double> projected = lights.projected_solid_angles();
  double projected_sum = 0.0;
  for (double p : projected) projected_sum += p;
  EXPECT_NEAR(projected_sum, kPi, 1e-6);
  const double albedo = 0.8;
  double reflected = 0.0;  // texel 0, view 0, unit radiance from every direction
  for (int j = 0; j < b.light_count(); ++j)
    reflected += b.value(0, 0, j).x * lights.cell_solid_angle();
  EXPECT_NEAR(reflected, albedo / kPi * kPi, 1e-5);
  for (int t = 0; t < b.texel_count(); ++t) {
    for (int v = 0; v < b.view_count(); ++v) {
      for (int j = 0; j < b.light_count(); ++j) {
        const double expected = albedo / kPi * projected[j] / lights.cell_solid_angle();
        const Rgb got = b.value(t, v, j);
        for (int c = 0; c < 3; ++c)
          ASSERT_NEAR(got[c], expected, 0.01 * expected)
              << "texel " << t << " view " << v << " light " << j;
      }
    }
  }
  // A Lambertian without meso-structure does not depend on the view at all (bitwise).
  EXPECT_TRUE(b.view_independent());
}

// A white Lambertian box bump (width w, height h) on a white base, seen from the zenith: the
// base is lit except for the box's shadow, of area w h tan(theta) (|cos phi| + |sin phi|).
TEST(BtfGenerator, BoxShadowAreaMatchesTheClosedForm) {
  constexpr float kWidth = 0.4f, kHeight = 0.1f;
  const LocalBrdf white{Rgb(1.0f), Rgb(0.0f), 1.0f};
  const MesoStructure box = box_bump_structure(kWidth, kHeight, white, white);
  BtfParams p = tiny(64, 1, 4);  // view grid of side 1: its only sample is the zenith
  const Btf b = generate_btf(box, p);
  const HemisphereGrid lights(4);
  double worst = 0.0;
  for (int j = 0; j < b.light_count(); ++j) {
    const Vec3d l = lights.direction(j);
    double mean = 0.0;
    for (int t = 0; t < b.texel_count(); ++t) mean += b.value(t, 0, j).x;
    mean /= b.texel_count();
    const double mean_cos = lights.projected_solid_angles()[j] / lights.cell_solid_angle();
    const double lit = mean / (mean_cos / kPi);  // fraction of the tile that is lit
    const double tan_theta = std::sqrt(1.0 - l.z * l.z) / l.z;
    const double phi = std::atan2(l.y, l.x);
    const double shadow =
        kWidth * kHeight * tan_theta * (std::abs(std::cos(phi)) + std::abs(std::sin(phi)));
    ASSERT_LT(kWidth + kHeight * tan_theta, 1.0);  // no overlap with the next tile's shadow
    // 128 x 128 sample points: the shadow's outline costs at most about 1 / 128 of the area.
    EXPECT_NEAR(lit, 1.0 - shadow, 0.008) << "light " << j << " tan " << tan_theta;
    worst = std::max(worst, std::abs(lit - (1.0 - shadow)));
  }
  std::printf("worst lit-fraction error %.4f\n", worst);
}

// A shadow ray that leaves the tile re-enters through the opposite side: the box next door
// shadows a point near the tile's edge.
TEST(BtfGenerator, RaysWrapAroundThePeriodicTile) {
  const LocalBrdf white{Rgb(1.0f), Rgb(0.0f), 1.0f};
  const MesoTracer tracer(box_bump_structure(0.4f, 0.1f, white, white));  // box on [0.3, 0.7]
  const Vec3 p(0.05f, 0.5f, 1e-4f);
  // Towards -x: the ray wraps to x = 1 and meets the box's +x wall at x = 0.7 after 0.35; it is
  // then at height 0.35 / tan(theta).
  const auto towards = [](double theta_deg) {
    const double t = theta_deg * kPi / 180.0;
    return Vec3(static_cast<float>(-std::sin(t)), 0.0f, static_cast<float>(std::cos(t)));
  };
  EXPECT_TRUE(tracer.occluded(p, towards(80.0)));   // 0.35 / 5.67 = 0.06 < 0.1
  EXPECT_FALSE(tracer.occluded(p, towards(60.0)));  // 0.35 / 1.73 = 0.20 > 0.1
  EXPECT_FALSE(tracer.occluded(p, {0.0f, 0.0f, 1.0f}));
  // Very grazing (0.6 degrees above the horizon): crosses the tile many times before it rises
  // above the box, and must be blocked.
  EXPECT_TRUE(tracer.occluded({0.5f, 0.05f, 1e-4f}, glm::normalize(Vec3(0.3f, 1.0f, 0.01f))));
  // The view ray from far above-left comes down through the tiling onto the box top.
  // The view ray through the box's centre (0.5, 0.5) from the -x side at tan(theta) = 3 starts
  // at x = 0.5 - 3 (1.001) + ..., several tiles away, and meets the box's -x wall (x = 0.3) at
  // height 0.2 / 3.
  const MesoTracer::Hit h =
      tracer.visible_point({0.5f, 0.5f}, glm::normalize(Vec3(-3.f, 0.f, 1.f)));
  ASSERT_TRUE(h.found);
  EXPECT_NEAR(h.position.x, 0.3f, 1e-5f);
  EXPECT_NEAR(h.position.z, 0.2f / 3.0f, 1e-5f);
  EXPECT_NEAR(h.geometric_normal.x, -1.0f, 1e-6f);
  EXPECT_EQ(h.brdf, 1);
}

// Masking: at grazing views the bumps hide the base. From the zenith the visible base fraction
// is the closed form 1 - 9 pi R^2 of the 3 x 3 caps of footprint radius R = 0.13.
TEST(BtfGenerator, BumpsHideTheBaseAtGrazingViews) {
  const MesoTracer tracer(make_btf_material("bumps", 128));
  const auto base_fraction = [&](Vec3 e) {
    int base = 0, total = 0;
    for (int y = 0; y < 100; ++y)
      for (int x = 0; x < 100; ++x, ++total) {
        const auto h = tracer.visible_point({(x + 0.5f) / 100.f, (y + 0.5f) / 100.f}, e);
        EXPECT_TRUE(h.found);
        base += h.brdf == 0;
      }
    return static_cast<double>(base) / total;
  };
  const double zenith = base_fraction({0.f, 0.f, 1.f});
  EXPECT_NEAR(zenith, 1.0 - 9.0 * kPi * 0.13 * 0.13, 0.01);
  const double at60 = base_fraction(glm::normalize(Vec3(std::sqrt(3.f), 0.f, 1.f)));
  const double at80 = base_fraction(glm::normalize(Vec3(5.67f, 0.f, 1.f)));
  std::printf("visible base: %.3f zenith, %.3f at 60 deg, %.3f at 80 deg\n", zenith, at60, at80);
  EXPECT_LT(at60, zenith - 0.03);
  EXPECT_LT(at80, at60 - 0.1);
}

// Directional albedo (btf_stats) of every material: positive, and at most the largest albedo of
// its BRDFs (each <= 1) plus the quadrature error of the view samples. Without meso-structure,
// the flat Lambertian's estimate is its albedo 0.8.
TEST(BtfGenerator, EveryMaterialConservesEnergy) {
  for (const std::string& name : btf_material_names()) {
    const MesoStructure meso = make_btf_material(name, 128);
    float brdf_albedo = 0.0f;
    for (const LocalBrdf& b : meso.brdfs)
      for (int c = 0; c < 3; ++c) brdf_albedo = std::max(brdf_albedo, b.diffuse[c] + b.specular[c]);
    ASSERT_LE(brdf_albedo, 1.0f) << name;
    const Btf btf = generate_btf(meso, tiny(8, 12, 4));
    const BtfStats s = btf_stats(btf);
    std::printf("%-8s albedo max %.3f %.3f %.3f, BRDF max %.3f\n", name.c_str(), s.albedo_max.x,
                s.albedo_max.y, s.albedo_max.z, brdf_albedo);
    EXPECT_EQ(s.non_finite, 0u) << name;
    for (int j = 0; j < btf.light_count(); ++j) {
      for (int c = 0; c < 3; ++c) {
        EXPECT_GT(s.albedo[j][c], 0.0f) << name << " light " << j;
        EXPECT_LE(s.albedo[j][c], brdf_albedo + 0.03f) << name << " light " << j << " ch " << c;
      }
    }
    if (name == "lambert") {
      EXPECT_NEAR(s.albedo_mean.x, 0.8, 1e-3);
    }
  }
}

// One bounce of interreflection adds light inside the bumps' concavities, never to a flat plane,
// and keeps the albedo below 1.
TEST(BtfGenerator, InterreflectionAddsLightWhereSurfacesSeeEachOther) {
  BtfParams p = tiny(8, 6, 4);
  const Btf flat0 = generate_btf(make_btf_material("lambert"), p);
  const MesoStructure bumps = make_btf_material("bumps", 128);
  const Btf direct = generate_btf(bumps, p);
  p.interreflection_samples = 16;
  const Btf flat1 = generate_btf(make_btf_material("lambert"), p);
  const Btf bounced = generate_btf(bumps, p);
  ASSERT_EQ(flat0.value_count(), flat1.value_count());
  EXPECT_EQ(std::memcmp(flat0.data().data(), flat1.data().data(), flat0.bytes()), 0);
  double sum0 = 0.0, sum1 = 0.0;
  for (std::size_t i = 0; i < direct.value_count(); ++i) {
    ASSERT_GE(bounced.data()[i], direct.data()[i]) << i;
    sum0 += direct.data()[i];
    sum1 += bounced.data()[i];
  }
  EXPECT_GT(sum1, 1.01 * sum0);
  const BtfStats s = btf_stats(bounced);
  for (int c = 0; c < 3; ++c) EXPECT_LE(s.albedo_max[c], 1.0f);
}

TEST(BtfGenerator, DeterministicBitwise) {
  BtfParams p = tiny(6, 3, 3);
  p.interreflection_samples = 4;
  const MesoStructure m = make_btf_material("weave", 64);
  const Btf a = generate_btf(m, p), b = generate_btf(m, p);
  ASSERT_EQ(a.bytes(), b.bytes());
  EXPECT_EQ(std::memcmp(a.data().data(), b.data().data(), a.bytes()), 0);
}

// The checker's raised squares are glossier than the base: in the mirror configuration (view
// and light both at the zenith) the raised texels are far brighter than the base texels.
TEST(BtfGenerator, CheckerRaisedSquaresAreGlossier) {
  const Btf b = generate_btf(make_btf_material("checker", 128), tiny(16, 1, 1));
  // 4 x 4 checks over 16 texels: texel (x, y) is raised when (x / 4 + y / 4) is even.
  double raised = 0.0, base = 0.0;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      const bool is_raised = ((x / 4) + (y / 4)) % 2 == 0;
      // The centre 2 x 2 texels of each check: away from the smoothed walls.
      if (x % 4 == 0 || x % 4 == 3 || y % 4 == 0 || y % 4 == 3) continue;
      (is_raised ? raised : base) += b.value(y * 16 + x, 0, 0).y;
    }
  EXPECT_GT(raised, 5.0 * base);
}

// The stone's height function is periodic with period 1: the lattice repeats its first row and
// column at x = 1 and y = 1 by construction, so a height function that were not periodic would
// show as a step across that seam far larger than any step inside the tile (its relief is 0.1,
// the largest interior step on a 512 lattice about 0.01).
TEST(BtfGenerator, StoneHeightFieldIsPeriodic) {
  constexpr int kGrid = 512, kSide = kGrid + 1;
  const MesoStructure m = make_btf_material("stone", kGrid);
  ASSERT_EQ(m.positions.size(), static_cast<std::size_t>(kSide) * kSide);
  const auto z = [&](int i, int j) {
    return m.positions[static_cast<std::size_t>(j) * kSide + i].z;
  };
  float interior = 0.0f, seam = 0.0f;
  for (int j = 0; j < kGrid; ++j)
    for (int i = 0; i + 1 < kGrid; ++i)
      interior =
          std::max({interior, std::abs(z(i + 1, j) - z(i, j)), std::abs(z(j, i + 1) - z(j, i))});
  for (int k = 0; k < kGrid; ++k)
    seam = std::max(
        {seam, std::abs(z(kGrid, k) - z(kGrid - 1, k)), std::abs(z(k, kGrid) - z(k, kGrid - 1))});
  std::printf("stone: largest step %.5f inside, %.5f across the seam; relief %.4f\n", interior,
              seam, m.max_height);
  EXPECT_GT(m.max_height, 0.08f);
  EXPECT_GT(interior, 0.0f);
  EXPECT_LE(seam, interior);
}

// Every one of the stone's local BRDFs covers a real part of the tile (the BTF varies in space
// by material as well as by geometry), the crevice floors lie below the plateaus, and the
// plateaus are the glossy ones.
TEST(BtfGenerator, StoneHasSpatiallyVaryingBrdfs) {
  const MesoStructure m = make_btf_material("stone", 256);
  ASSERT_EQ(m.brdfs.size(), 5u);
  std::vector<double> share(m.brdfs.size(), 0.0), mean_z(m.brdfs.size(), 0.0);
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const int b = m.triangle_brdf[t];
    share[b] += 1.0;
    for (int k = 0; k < 3; ++k) mean_z[b] += m.positions[m.indices[3 * t + k]].z / 3.0;
  }
  for (std::size_t b = 0; b < share.size(); ++b) {
    mean_z[b] /= share[b];
    share[b] /= static_cast<double>(m.triangle_count());
    std::printf("stone BRDF %zu: %.3f of the triangles, mean height %.4f\n", b, share[b],
                mean_z[b]);
    EXPECT_GT(share[b], 0.03) << b;
  }
  for (std::size_t b = 1; b < share.size(); ++b) EXPECT_LT(mean_z[0], mean_z[b]) << b;
  for (std::size_t b = 0; b + 1 < share.size(); ++b) {
    EXPECT_LT(mean_z[b], mean_z[4]) << b;
    EXPECT_GT(m.brdfs[b].roughness, 2.0f * m.brdfs[4].roughness) << b;
  }
}

// Self-shadowing and masking. From the zenith light a height field casts no shadow: every
// texel of the BTF is lit, and no point of a plateau is dark; the only dark points are a few in
// the crevices' sharp concave creases, where the shadow ray's offset along one triangle's normal
// ends up under its steep neighbour. Towards the horizon the crevices and the flanks facing away
// fall into shadow, several times more than on the flatter stucco; at grazing views the grains
// hide the crevice floors.
TEST(BtfGenerator, StoneShadowsAndMasksAtGrazingAngles) {
  const Btf top = generate_btf(make_btf_material("stone", 128), tiny(16, 1, 1));
  for (int t = 0; t < top.texel_count(); ++t)
    for (int c = 0; c < 3; ++c) ASSERT_GT(top.value(t, 0, 0)[c], 0.0f) << "texel " << t;

  const MesoTracer stone(make_btf_material("stone", 256));
  const MesoTracer stucco(make_btf_material("stucco", 256));
  const auto at = [](double theta_deg) {
    const double t = theta_deg * kPi / 180.0;
    return Vec3(static_cast<float>(std::sin(t)), 0.0f, static_cast<float>(std::cos(t)));
  };
  constexpr int kN = 100;
  constexpr int kPlateau = 4;
  // Fraction of the points seen from the zenith that are dark under a light at theta_deg, and
  // how many of them lie on a plateau.
  const auto shadowed = [&](const MesoTracer& tracer, double theta_deg, int* plateau_dark) {
    int dark = 0;
    for (int y = 0; y < kN; ++y)
      for (int x = 0; x < kN; ++x) {
        const auto h = tracer.visible_point({(x + 0.5f) / kN, (y + 0.5f) / kN}, {0.f, 0.f, 1.f});
        EXPECT_TRUE(h.found);
        const Vec3 l = at(theta_deg);
        const bool d = glm::dot(h.shading_normal, l) <= 0.0f ||
                       glm::dot(h.geometric_normal, l) <= 0.0f ||
                       tracer.occluded(h.position + 1e-4f * h.geometric_normal, l);
        dark += d;
        if (plateau_dark) *plateau_dark += d && h.brdf == kPlateau;
      }
    return static_cast<double>(dark) / (kN * kN);
  };
  const auto crevices_seen = [&](double theta_deg) {
    int floor = 0;
    for (int y = 0; y < kN; ++y)
      for (int x = 0; x < kN; ++x)
        floor += stone.visible_point({(x + 0.5f) / kN, (y + 0.5f) / kN}, at(theta_deg)).brdf == 0;
    return static_cast<double>(floor) / (kN * kN);
  };
  int plateau_dark_at_zenith = 0, plateau_dark_at_85 = 0;
  const double s0 = shadowed(stone, 0.0, &plateau_dark_at_zenith);
  const double s45 = shadowed(stone, 45.0, nullptr), s75 = shadowed(stone, 75.0, nullptr);
  const double s85 = shadowed(stone, 85.0, &plateau_dark_at_85);
  const double stucco75 = shadowed(stucco, 75.0, nullptr);
  const double c0 = crevices_seen(0.0), c75 = crevices_seen(75.0);
  std::printf(
      "stone shadowed: %.4f at 0, %.3f at 45, %.3f at 75, %.3f at 85 deg (stucco %.3f at 75); "
      "plateau points dark: %d at 0, %d at 85 deg; crevice floor seen %.3f from the zenith, %.3f "
      "at 75 deg\n",
      s0, s45, s75, s85, stucco75, plateau_dark_at_zenith, plateau_dark_at_85, c0, c75);
  EXPECT_EQ(plateau_dark_at_zenith, 0);
  EXPECT_GT(plateau_dark_at_85, 0);
  EXPECT_LT(s0, 0.002);
  EXPECT_LT(s0, s45);
  EXPECT_LT(s45, s75);
  EXPECT_LT(s75, s85);
  EXPECT_GT(s75, 0.3);
  EXPECT_GT(s75, 3.0 * stucco75);
  EXPECT_GT(c0, 0.1);
  EXPECT_LT(c75, 0.5 * c0);
}

// The stone's BTF is not separable into a texture times one ABRDF: the texel x (view, light)
// matrix of each channel is far from rank 1 (the flat Lambertian's is rank 1 to rounding).
TEST(BtfGenerator, StoneBtfIsNotSeparable) {
  const auto rank1_residual = [](const Btf& b, int c) {
    const int rows = b.texel_count(), cols = b.view_count() * b.light_count();
    const auto a = [&](int r, int k) {
      return static_cast<double>(b.value(r, k / b.light_count(), k % b.light_count())[c]);
    };
    // Power iteration on A^T A for the largest singular value.
    std::vector<double> v(static_cast<std::size_t>(cols), 1.0), u(static_cast<std::size_t>(rows));
    double sigma2 = 0.0, total = 0.0;
    for (int r = 0; r < rows; ++r)
      for (int k = 0; k < cols; ++k) total += a(r, k) * a(r, k);
    for (int it = 0; it < 200; ++it) {
      for (int r = 0; r < rows; ++r) {
        double s = 0.0;
        for (int k = 0; k < cols; ++k) s += a(r, k) * v[k];
        u[r] = s;
      }
      double norm = 0.0;
      for (int k = 0; k < cols; ++k) {
        double s = 0.0;
        for (int r = 0; r < rows; ++r) s += a(r, k) * u[r];
        v[k] = s;
        norm += s * s;
      }
      norm = std::sqrt(norm);
      for (double& x : v) x /= norm;
      double uu = 0.0;
      for (double x : u) uu += x * x;
      sigma2 = uu;  // |A v|^2 with the previous unit v
    }
    return std::sqrt(std::max(0.0, total - sigma2) / total);
  };
  const BtfParams p = tiny(16, 4, 4);
  const Btf flat = generate_btf(make_btf_material("lambert"), p);
  const Btf stone = generate_btf(make_btf_material("stone", 128), p);
  for (int c = 0; c < 3; ++c) {
    const double f = rank1_residual(flat, c), s = rank1_residual(stone, c);
    std::printf("channel %d: rank-1 relative residual lambert %.2e, stone %.3f\n", c, f, s);
    EXPECT_LT(f, 1e-3);
    EXPECT_GT(s, 0.2);
  }
}

TEST(BtfGenerator, ParametersAreValidated) {
  BtfParams p;
  p.resolution = 0;
  EXPECT_THROW(p.validate(), ParameterError);
  p = BtfParams{};
  p.view_side = 65;
  EXPECT_THROW(p.validate(), ParameterError);
  EXPECT_THROW(make_btf_material("velvet"), ParameterError);
  EXPECT_THROW(box_bump_structure(1.2f, 0.1f, {}, {}), ParameterError);
}

}  // namespace
}  // namespace prt
