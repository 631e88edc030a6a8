#pragma once
// The tiny sphere-over-plane scene as the frame-loop tests use it: its exact transfer T, small
// synthetic BTFs through the `full` material, and two sun-and-sky lights. Built once per test
// program (tiny_frame_scene()); tests compress T with whatever backends they exercise.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "prtlab/btf/btf_generator.h"
#include "prtlab/btf/btf_materials.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/geometry/scene.h"
#include "prtlab/lighting/environment_map.h"
#include "prtlab/render/btf_shading.h"
#include "prtlab/sphere/cubemap.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/transfer/transfer_matrix.h"
#include "prtlab/transfer/visibility.h"

namespace prt::testing {

/// Small synthetic BTFs for every part of `scene` (8 x 8 texels, 6 x 6 views, the scene's
/// local grid as lights): cheap enough to generate in every test program.
inline std::vector<std::shared_ptr<const Btf>> tiny_scene_btfs(const Scene& scene) {
  BtfParams p;
  p.resolution = 8;
  p.view_side = 6;
  p.light_side = scene.desc.local_grid;
  p.supersampling = 1;
  p.geometry_grid = 64;
  std::vector<std::shared_ptr<const Btf>> btfs;
  for (const auto& part : scene.desc.parts)
    btfs.push_back(std::make_shared<const Btf>(generate_btf(make_btf_material(part.btf, 64), p)));
  return btfs;
}

struct TinyFrameScene {
  Scene scene =
      load_scene(std::filesystem::path(PRTLAB_SOURCE_DIR) / "scenes/tiny-sphere-plane.toml");
  TransferMatrix transfer = [this] {
    const auto& d = scene.desc;
    TransferParams tp;
    tp.cubemap_resolution = d.cubemap_resolution;
    tp.local_grid = d.local_grid;
    tp.supersampling = d.supersampling;
    tp.show_progress = false;
    return compute_transfer(scene.mesh, tp).transfer;
  }();
  CubemapLayout layout{scene.desc.cubemap_resolution};
  HemisphereGrid grid{scene.desc.local_grid};
  ShadingMaterials materials = [this] {
    ShadingMaterials m;
    m.part_material = compress_part_materials(tiny_scene_btfs(scene), "full", {});
    return m;
  }();
  Cubemap sky = SunSky{}.to_cubemap(8, 2);
  Cubemap sky2 = [] {
    SunSky s;
    s.sun_dir = {-0.6, 0.4, -0.2};
    s.sun = Rgb(900.f, 1200.f, 1500.f);
    return s.to_cubemap(8, 2);
  }();

  /// T compressed by a registered backend at `params`.
  std::shared_ptr<const CompressedTransfer> compress(
      const std::string& backend, const std::map<std::string, std::string>& params = {}) const {
    return CompressorRegistry::instance()
        .create(backend, params)
        ->compress({transfer, nullptr, layout, grid}, Progress::null());
  }
};

inline const TinyFrameScene& tiny_frame_scene() {
  static const TinyFrameScene s;
  return s;
}

}  // namespace prt::testing
