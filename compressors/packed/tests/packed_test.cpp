// Material `packed`: every stored value within its quantisation step of the BTF's; the shaded
// image within the bound that step implies (the step of each read vector times its weight, times
// |L*|, summed); the OpenCL image equals the C++ reference for each storage kind; the tiled
// layout changes where values live, never what is shaded.
#include "packed/packed.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>

#include "prtlab/base/error.h"
#include "prtlab/compress/material_error.h"
#include "prtlab/geometry/scene.h"
#include "prtlab/numeric/float16.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/render/btf_shading.h"
#include "prtlab/storage/archive.h"
#include "support/temp_dir.h"
#include "support/tiny_frame_scene.h"

namespace prt::packed {
namespace {
namespace fs = std::filesystem;

const fs::path g_cache = prt::testing::use_private_cache("packed_material");

struct Tiny {
  Scene scene = load_scene(fs::path(PRTLAB_SOURCE_DIR) / "scenes/tiny-sphere-plane.toml");
  std::vector<std::shared_ptr<const Btf>> btfs;
  GBuffer gbuffer;
  LocalRadiance radiance;

  Tiny() {
    btfs = prt::testing::tiny_scene_btfs(scene);
    CameraOverrides size;
    size.width = 64;
    size.height = 48;
    gbuffer = render_gbuffer(scene.mesh, scene_camera(scene, "front", size));
    const int m = scene.desc.local_grid * scene.desc.local_grid;
    radiance = LocalRadiance(RadianceBasis::kPixel, m, scene.mesh.positions.size());
    for (std::size_t i = 0; i < radiance.values.size(); ++i)
      radiance.values[i] = Rgb(static_cast<float>(i % 7) * 0.3f, static_cast<float>(i % 5) * 0.2f,
                               static_cast<float>(i % 3) * 0.5f);
  }
  ShadingMaterials materials(const std::string& name,
                             const std::map<std::string, std::string>& params) const {
    ShadingMaterials m;
    m.part_material = compress_part_materials(btfs, name, params);
    return m;
  }
};

const Tiny& tiny() {
  static const Tiny t;
  return t;
}

RgbImage cpp_image(const Tiny& t, const ShadingMaterials& m, TexelFilter filter) {
  ShadingOptions o;
  o.filter = filter;
  o.background = false;
  return shade_frame_reference(t.gbuffer, t.scene.mesh, m, t.radiance, nullptr, o);
}

TEST(PackedMaterial, EveryValueWithinItsQuantisationStep) {
  const Tiny& t = tiny();
  for (const auto storage : {Storage::kHalf, Storage::kByte}) {
    for (const auto& btf : t.btfs) {
      const PackedMaterial m(*btf, storage, 4);
      double worst = 0.0;  // largest error as a fraction of its bound
      for (int tx = 0; tx < btf->texel_count(); ++tx)
        for (int v = 0; v < btf->view_count(); ++v)
          for (int j = 0; j < btf->light_count(); ++j) {
            const Rgb a = btf->value(tx, v, j), b = m.reflectance(tx, v, j);
            for (int c = 0; c < 3; ++c) {
              const float bound = m.value_error_bound(tx, v, 3 * j + c);
              const float err = std::abs(a[c] - b[c]);
              ASSERT_LE(err, bound) << storage_name(storage) << " texel " << tx << " view " << v;
              if (bound > 0) worst = std::max(worst, static_cast<double>(err / bound));
            }
          }
      // The bound is the step, not a loose multiple of it: some value uses most of it.
      EXPECT_GT(worst, 0.5) << storage_name(storage);
      const MaterialError e = material_error(m, *btf);
      EXPECT_LE(e.relative_l2, m.declared_error_bound()) << storage_name(storage);
      EXPECT_GT(e.relative_l2, 0.0);
    }
  }
}

// |B~ - B| per channel <= sum over the read vectors of weight x sum_j step_j |L*_j| (+ float
// rounding of the two sums).
TEST(PackedMaterial, ShadedImageWithinTheDerivedBound) {
  const Tiny& t = tiny();
  const ShadingMaterials full = t.materials("full", {});
  for (const std::string storage : {"f16", "u8"}) {
    const ShadingMaterials packed = t.materials("packed", {{"storage", storage}});
    for (const auto filter : {TexelFilter::kNearest, TexelFilter::kBilinear}) {
      const RgbImage a = cpp_image(t, full, filter), b = cpp_image(t, packed, filter);
      const GBuffer& g = t.gbuffer;
      const int m = t.radiance.dim;
      std::vector<Rgb> lstar(static_cast<std::size_t>(m));
      std::size_t checked = 0;
      double used = 0.0;
      for (std::size_t i = 0; i < g.pixel_count(); ++i) {
        if (g.triangle[i] < 0) continue;
        const std::uint32_t* v = &t.scene.mesh.indices[3 * static_cast<std::size_t>(g.triangle[i])];
        const float w1 = g.bary[2 * i], w2 = g.bary[2 * i + 1], w0 = 1.0f - w1 - w2;
        const auto l0 = t.radiance.vertex(v[0]), l1 = t.radiance.vertex(v[1]),
                   l2 = t.radiance.vertex(v[2]);
        for (int j = 0; j < m; ++j) lstar[j] = w0 * l0[j] + w1 * l1[j] + w2 * l2[j];
        const auto* mat = dynamic_cast<const PackedMaterial*>(
            packed.part_material[static_cast<std::size_t>(g.part[i])].get());
        ASSERT_NE(mat, nullptr);
        const Vec2 uv(g.uv[2 * i], g.uv[2 * i + 1]);
        const Vec3 e(g.view_local[4 * i], g.view_local[4 * i + 1], g.view_local[4 * i + 2]);
        const BtfTexelSamples ts = btf_texel_samples(mat->sampling().resolution, uv, filter);
        BtfViewSamples vs;
        if (mat->stored_views() == 1)
          vs.weight = {1.f, 0.f, 0.f, 0.f};
        else
          vs = btf_view_samples(mat->sampling().view_side, e);
        Vec3d bound(0.0), magnitude(0.0);
        for (int k = 0; k < ts.count; ++k)
          for (int q = 0; q < 4; ++q) {
            const double w = static_cast<double>(ts.weight[k]) * vs.weight[q];
            if (w == 0.0) continue;
            for (int j = 0; j < m; ++j)
              for (int c = 0; c < 3; ++c) {
                bound[c] += w * mat->value_error_bound(ts.texel[k], vs.view[q], 3 * j + c) *
                            std::abs(lstar[j][c]);
                magnitude[c] +=
                    w * std::abs(mat->reflectance(ts.texel[k], vs.view[q], j)[c] * lstar[j][c]);
              }
          }
        for (int c = 0; c < 3; ++c) {
          const double err = std::abs(static_cast<double>(a.pixels[i][c]) - b.pixels[i][c]);
          const double slack = 1e-6 * (magnitude[c] + bound[c]) + 1e-30;
          ASSERT_LE(err, bound[c] + slack) << storage << " pixel " << i << " channel " << c;
          if (bound[c] > 0) used = std::max(used, err / bound[c]);
        }
        ++checked;
      }
      EXPECT_GT(checked, 100u);
      EXPECT_GT(used, 0.01) << storage << ": the bound should not be vacuous";
    }
  }
}

TEST(PackedMaterial, OpenClEqualsCppForEveryStorageKind) {
  ClContext* ctx = default_context();
  if (ctx == nullptr) GTEST_SKIP() << "no OpenCL device";
  const Tiny& t = tiny();
  for (const std::string storage : {"f16", "u8"})
    for (const std::string tile : {"1", "3"})
      for (const auto filter : {TexelFilter::kNearest, TexelFilter::kBilinear})
        for (const bool cache : {true, false}) {
          const ShadingMaterials m = t.materials("packed", {{"storage", storage}, {"tile", tile}});
          ShadingOptions o;
          o.filter = filter;
          o.background = false;
          o.cache_view_vectors = cache;
          DeviceBtfShader shader(*ctx, t.scene.mesh, m, nullptr, o);
          shader.set_gbuffer(t.gbuffer);
          shader.set_radiance(t.radiance);
          shader.shade();
          const RgbImage gpu = shader.read_image();
          const RgbImage ref = cpp_image(t, m, filter);
          double err = 0, peak = 0;
          for (std::size_t i = 0; i < ref.pixels.size(); ++i)
            for (int c = 0; c < 3; ++c) {
              err =
                  std::max(err, static_cast<double>(std::abs(gpu.pixels[i][c] - ref.pixels[i][c])));
              peak = std::max(peak, static_cast<double>(ref.pixels[i][c]));
            }
          EXPECT_GT(peak, 0.0);
          EXPECT_LE(err, 1e-5 * peak) << storage << " tile " << tile << (cache ? " cache" : "");
          const std::uint64_t per_vector =
              static_cast<std::uint64_t>(t.radiance.dim) * 3 * (storage == "f16" ? 2 : 1) +
              (storage == "u8" ? 4 : 0);
          EXPECT_GT(shader.bytes_per_pass().view_cache, shader.hit_pixels() * per_vector);
        }
}

TEST(PackedMaterial, TiledLayoutIsAPermutationThatShadesTheSame) {
  for (const int res : {1, 5, 8, 13})
    for (const int tile : {1, 2, 4, 7}) {
      const auto slots = tiled_texel_slots(res, tile);
      std::vector<int> seen(slots.size(), 0);
      for (const auto s : slots) {
        ASSERT_GE(s, 0);
        ASSERT_LT(static_cast<std::size_t>(s), slots.size());
        ++seen[static_cast<std::size_t>(s)];
      }
      for (const int n : seen) EXPECT_EQ(n, 1);
      if (tile == 1) {
        for (std::size_t i = 0; i < slots.size(); ++i) EXPECT_EQ(slots[i], static_cast<int>(i));
      }
    }
  EXPECT_EQ(tiled_texel_slots(4, 2),
            (std::vector<std::int32_t>{0, 1, 4, 5, 2, 3, 6, 7, 8, 9, 12, 13, 10, 11, 14, 15}));
  const Tiny& t = tiny();
  for (const auto filter : {TexelFilter::kNearest, TexelFilter::kBilinear}) {
    const RgbImage a = cpp_image(t, t.materials("packed", {{"tile", "1"}}), filter);
    const RgbImage b = cpp_image(t, t.materials("packed", {{"tile", "4"}}), filter);
    EXPECT_EQ(std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(Rgb)), 0);
  }
}

TEST(PackedMaterial, RefusesValuesItCannotStore) {
  const Btf negative("neg", 2, 1, 2, std::vector<float>(2 * 2 * 4 * 3, 0.5f));
  std::vector<float> v(2 * 2 * 4 * 3, 0.5f);
  v[7] = -0.25f;
  EXPECT_THROW(PackedMaterial(Btf("neg", 2, 1, 2, v), Storage::kByte, 4), ParameterError);
  v[7] = 1e5f;
  EXPECT_THROW(PackedMaterial(Btf("big", 2, 1, 2, v), Storage::kHalf, 4), ParameterError);
  EXPECT_NO_THROW(PackedMaterial(Btf("big", 2, 1, 2, v), Storage::kByte, 4));
  v[7] = std::nanf("");
  EXPECT_THROW(PackedMaterial(Btf("nan", 2, 1, 2, v), Storage::kByte, 4), ParameterError);
  EXPECT_THROW(PackedMaterial(negative, Storage::kByte, 0), ParameterError);
}

TEST(PackedMaterial, SaveLoadIsExactAndDamageIsRefused) {
  const Tiny& t = tiny();
  prt::testing::TempDir dir;
  for (const std::string storage : {"f16", "u8"}) {
    const auto m = compress_material("packed", {{"storage", storage}}, t.btfs[0]);
    const fs::path file = dir.path() / (storage + ".prt");
    save_material(*m, file);
    const auto back = load_material(file);
    const auto* a = dynamic_cast<const PackedMaterial*>(m.get());
    const auto* b = dynamic_cast<const PackedMaterial*>(back.get());
    ASSERT_NE(b, nullptr);
    EXPECT_EQ(a->halves(), b->halves());
    EXPECT_EQ(a->bytes(), b->bytes());
    EXPECT_EQ(a->scales(), b->scales());
    EXPECT_EQ(a->texel_slot(), b->texel_slot());
    EXPECT_EQ(a->declared_error_bound(), b->declared_error_bound());
    EXPECT_EQ(b->storage().total_bytes(), a->storage().total_bytes());
  }
  // Damaged state: each edit is refused with the file named.
  const fs::path good = dir.path() / "u8.prt";
  const ArchiveReader r = ArchiveReader::open(good);
  auto rewrite = [&](const std::string& name, auto edit_meta, auto edit_scales) {
    ArchiveWriter w(r.kind(), r.kind_version());
    for (const auto& [k, v] : r.meta().items()) w.add_meta(k, v);
    edit_meta(w.meta());
    const auto codes = r.view<std::uint8_t>("u8");
    const auto view = r.view<float>("scales");
    std::vector<float> scales(view.begin(), view.end());
    edit_scales(scales);
    w.add_section("u8", codes);
    w.add_section("scales", scales);
    const fs::path f = dir.path() / name;
    w.write(f);
    return f;
  };
  const auto keep = [](auto&) {};
  const std::vector<fs::path> damaged = {
      rewrite(
          "version.prt", [](nlohmann::json& m) { m["packed"]["format_version"] = 99; }, keep),
      rewrite(
          "storage.prt", [](nlohmann::json& m) { m["packed"]["storage"] = "f32"; }, keep),
      rewrite(
          "tile.prt", [](nlohmann::json& m) { m["packed"]["tile"] = 0; }, keep),
      rewrite(
          "views.prt", [](nlohmann::json& m) { m["packed"]["stored_views"] = 5; }, keep),
      rewrite("scale.prt", keep, [](std::vector<float>& s) { s[3] = -1.0f; }),
      rewrite("nan.prt", keep, [](std::vector<float>& s) { s[0] = std::nanf(""); }),
      rewrite("short.prt", keep, [](std::vector<float>& s) { s.pop_back(); })};
  for (const auto& f : damaged) {
    try {
      load_material(f);
      ADD_FAILURE() << f << " was loaded";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), f);
    }
  }
  EXPECT_NE(load_material(good), nullptr);
}

}  // namespace
}  // namespace prt::packed
