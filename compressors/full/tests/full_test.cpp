// Material `full`: shading through it is the shading of the raw BTF it wraps. The C++ path is
// bit-identical to shading the BTF directly (the loop the renderer ran before materials
// existed, written out here), the OpenCL path within float rounding of it; storage, FLOPs and
// the archive's refusals of damaged state.
#include "full/full.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>

#include "prtlab/base/error.h"
#include "prtlab/btf/btf_generator.h"
#include "prtlab/btf/btf_materials.h"
#include "prtlab/geometry/scene.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/render/btf_shading.h"
#include "prtlab/storage/archive.h"
#include "support/temp_dir.h"
#include "support/tiny_frame_scene.h"

namespace prt::full {
namespace {
namespace fs = std::filesystem;

const fs::path g_cache = prt::testing::use_private_cache("full_material");

struct Tiny {
  Scene scene = load_scene(fs::path(PRTLAB_SOURCE_DIR) / "scenes/tiny-sphere-plane.toml");
  std::vector<std::shared_ptr<const Btf>> btfs;
  ShadingMaterials materials;
  GBuffer gbuffer;
  LocalRadiance radiance;

  Tiny() {
    btfs = prt::testing::tiny_scene_btfs(scene);
    materials.part_material = compress_part_materials(btfs, "full", {});
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
};

const Tiny& tiny() {
  static const Tiny t;
  return t;
}

// The shading of the raw BTFs, as shade_frame_reference computed it before materials: L*
// interpolated in float, then Btf::shade; misses black.
RgbImage shade_btfs_directly(const Tiny& t, TexelFilter filter) {
  const GBuffer& g = t.gbuffer;
  const int m = t.radiance.dim;
  RgbImage image(g.width, g.height);
  std::vector<Rgb> lstar(static_cast<std::size_t>(m));
  for (int y = 0; y < g.height; ++y)
    for (int x = 0; x < g.width; ++x) {
      const std::size_t i = g.index(x, y);
      if (g.triangle[i] < 0) continue;
      const std::uint32_t* v = &t.scene.mesh.indices[3 * static_cast<std::size_t>(g.triangle[i])];
      const float w1 = g.bary[2 * i], w2 = g.bary[2 * i + 1], w0 = 1.0f - w1 - w2;
      const auto l0 = t.radiance.vertex(v[0]), l1 = t.radiance.vertex(v[1]),
                 l2 = t.radiance.vertex(v[2]);
      for (int j = 0; j < m; ++j) lstar[j] = w0 * l0[j] + w1 * l1[j] + w2 * l2[j];
      const Btf& btf = *t.btfs[static_cast<std::size_t>(g.part[i])];
      image.at(x, y) =
          btf.shade(Vec2(g.uv[2 * i], g.uv[2 * i + 1]),
                    Vec3(g.view_local[4 * i], g.view_local[4 * i + 1], g.view_local[4 * i + 2]),
                    lstar, filter);
    }
  return image;
}

TEST(FullMaterial, CppShadingIsBitIdenticalToShadingTheBtfs) {
  const Tiny& t = tiny();
  for (const auto filter : {TexelFilter::kNearest, TexelFilter::kBilinear}) {
    ShadingOptions o;
    o.filter = filter;
    o.background = false;
    const RgbImage via_material =
        shade_frame_reference(t.gbuffer, t.scene.mesh, t.materials, t.radiance, nullptr, o);
    const RgbImage direct = shade_btfs_directly(t, filter);
    ASSERT_EQ(via_material.pixels.size(), direct.pixels.size());
    EXPECT_EQ(std::memcmp(via_material.pixels.data(), direct.pixels.data(),
                          direct.pixels.size() * sizeof(Rgb)),
              0)
        << (filter == TexelFilter::kNearest ? "nearest" : "bilinear");
  }
}

TEST(FullMaterial, OpenClShadingEqualsShadingTheBtfsToFloatRounding) {
  ClContext* ctx = default_context();
  if (ctx == nullptr) GTEST_SKIP() << "no OpenCL device";
  const Tiny& t = tiny();
  for (const auto filter : {TexelFilter::kNearest, TexelFilter::kBilinear})
    for (const bool cache : {true, false}) {
      ShadingOptions o;
      o.filter = filter;
      o.background = false;
      o.cache_view_vectors = cache;
      DeviceBtfShader shader(*ctx, t.scene.mesh, t.materials, nullptr, o);
      shader.set_gbuffer(t.gbuffer);
      shader.set_radiance(t.radiance);
      shader.shade();
      const RgbImage gpu = shader.read_image();
      const RgbImage direct = shade_btfs_directly(t, filter);
      double err = 0, peak = 0;
      for (std::size_t i = 0; i < direct.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) {
          err =
              std::max(err, static_cast<double>(std::abs(gpu.pixels[i][c] - direct.pixels[i][c])));
          peak = std::max(peak, static_cast<double>(direct.pixels[i][c]));
        }
      EXPECT_GT(peak, 0.0);
      EXPECT_LE(err, 1e-5 * peak) << (cache ? "view cache" : "single pass");
      // The traffic accounting is the raw BTF's: 4 view vectors of M RGB floats per hit pixel
      // and texel, plus L* of 3 vertices.
      const std::uint64_t vector = static_cast<std::uint64_t>(t.radiance.dim) * 12;
      const std::uint64_t texels = filter == TexelFilter::kBilinear ? 4 : 1;
      EXPECT_EQ(shader.bytes_read_per_frame(), shader.hit_pixels() * (4 * texels + 3) * vector);
    }
}

TEST(FullMaterial, StorageFlopsAndBasisAreTheBtfs) {
  const Tiny& t = tiny();
  const auto& m = *t.materials.part_material[0];
  const Btf& b = *t.btfs[0];
  EXPECT_EQ(m.storage().total_bytes(), b.bytes());
  EXPECT_EQ(m.flops_per_pixel(), 10.0 * b.light_count());
  EXPECT_EQ(m.light_basis(), MaterialLightBasis::pixel_bins(b.light_side()));
  EXPECT_EQ(m.declared_error_bound(), 0.0);
  // Parts sharing a BTF share its material.
  const auto shared = compress_part_materials(std::vector{t.btfs[0], t.btfs[0]}, "full", {});
  EXPECT_EQ(shared[0], shared[1]);
}

TEST(FullMaterial, LoadRefusesDamagedState) {
  const Tiny& t = tiny();
  prt::testing::TempDir dir;
  const fs::path good = dir.path() / "good.prt";
  save_material(*t.materials.part_material[0], good);
  const ArchiveReader r = ArchiveReader::open(good);
  auto rewrite = [&](const std::string& name, auto edit_meta, bool drop_values) {
    ArchiveWriter w(r.kind(), r.kind_version());
    for (const auto& [k, v] : r.meta().items()) w.add_meta(k, v);
    edit_meta(w.meta());
    const auto rgb = r.view<float>("rgb");
    w.add_section("rgb", drop_values ? rgb.first(rgb.size() - 3) : rgb);
    const fs::path f = dir.path() / name;
    w.write(f);
    return f;
  };
  const auto version = rewrite(
      "version.prt", [](nlohmann::json& m) { m["full"]["format_version"] = 99; }, false);
  const auto size = rewrite(
      "size.prt", [](nlohmann::json& m) { m["full"]["resolution"] = 9; }, false);
  const auto short_rgb = rewrite(
      "short.prt", [](nlohmann::json&) {}, true);
  for (const auto& f : {version, size, short_rgb}) {
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
}  // namespace prt::full
