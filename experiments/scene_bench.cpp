#include "scene_bench.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "prtlab/base/error.h"
#include "prtlab/compress/compression_stage.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/lighting/environment_map.h"
#include "prtlab/render/frame_renderer.h"
#include "prtlab/render/image_error.h"

namespace prt::experiments {
namespace {

// The procedural sun of the "sun" environments: a sky of unit-ish radiance and a sun `ratio`
// times brighter, small (0.5 degrees, the real sun's angular radius is 0.27) so that it falls
// into one or two cubemap pixels: the case where low-frequency bases fail most.
SunSky sun_environment(double ratio, bool sky, double rotate_deg = 0) {
  SunSky s;
  s.sky = sky ? Rgb{0.6f, 0.75f, 1.0f} : Rgb{0.0f};
  s.ground = sky ? Rgb{0.2f, 0.18f, 0.15f} : Rgb{0.0f};
  const float r = static_cast<float>(ratio * 0.75);
  s.sun = {r, r * 0.95f, r * 0.85f};
  s.sun_radius_rad = 0.5 * 3.14159265358979323846 / 180.0;
  const double a = rotate_deg * 3.14159265358979323846 / 180.0;
  const Vec3d d{0.3, 0.8, 0.5};
  // About +y, +x towards -z (rotate_latlong_y's convention).
  s.sun_dir =
      Vec3d{std::cos(a) * d.x + std::sin(a) * d.z, d.y, -std::sin(a) * d.x + std::cos(a) * d.z};
  return s;
}

}  // namespace

double exposure_of(const RgbImage& img, std::span<const std::uint8_t> mask) {
  std::vector<double> lum;
  for (std::size_t i = 0; i < img.pixels.size(); ++i) {
    if (!mask.empty() && !mask[i]) continue;
    const Rgb& p = img.pixels[i];
    const double y = 0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z;
    if (std::isfinite(y)) lum.push_back(y);
  }
  if (lum.empty()) return 0;
  const std::size_t k = static_cast<std::size_t>(0.99 * static_cast<double>(lum.size() - 1));
  std::nth_element(lum.begin(), lum.begin() + static_cast<std::ptrdiff_t>(k), lum.end());
  return lum[k] > 0 ? std::log2(0.9 / lum[k]) : 0.0;
}

Cubemap environment_cubemap(const EnvironmentSpec& e, int resolution, double rotate_deg) {
  if (e.sun_ratio)
    return sun_environment(*e.sun_ratio, !e.sun_only, rotate_deg).to_cubemap(resolution);
  const LatLongImage img = load_latlong_exr(e.file);
  return resample_to_cubemap(rotate_deg == 0 ? img : rotate_latlong_y(img, rotate_deg), resolution);
}

void check_environments(const ExperimentSpec& spec) {
  for (const auto& e : spec.environments) {
    if (e.sun_ratio) continue;
    try {
      (void)load_latlong_exr(e.file);
    } catch (const Error& err) {
      throw InputError(spec.file, fmt::format("environment '{}' ({}) is not a readable map: {}",
                                              e.name, e.file, err.what()));
    }
  }
}

SceneBench prepare_bench(const SceneVariant& variant, const ExperimentSpec& spec, StageCache& cache,
                         const BenchOptions& o) {
  SceneBench b;
  b.variant = variant;
  const SceneDesc desc = parse_scene(variant.file);
  std::vector<std::string> names = spec.backends;
  names.push_back(spec.reference);
  if (spec.kind == ExperimentKind::kEqualStorage && !spec.target.megabytes)
    names.push_back(spec.target.backend);
  std::sort(names.begin(), names.end());
  names.erase(std::unique(names.begin(), names.end()), names.end());
  PrepareOptions popt;
  popt.cache = o.cache_mode;
  popt.show_progress = o.show_progress;
  b.prepared = prepare_scene_for(desc, names, cache, popt);
  const TransferMatrix& t = b.prepared.transfer.result.transfer;
  b.info = {{"scene", variant.name},
            {"base", variant.base},
            {"file", variant.file.string()},
            {"overrides", variant.overrides},
            {"vertices", t.vertex_count()},
            {"local_grid", desc.local_grid},
            {"cubemap_resolution", desc.cubemap_resolution},
            {"supersampling", desc.supersampling},
            {"M", t.local_count()},
            {"N", t.cols()},
            {"nnz", t.nnz()},
            {"frobenius_sq",
             [&] {
               // ||T||_F^2, in double: turns a relative Frobenius error into the papers' SE.
               double sq = 0;
               for (std::size_t i = 0; i < t.nnz(); ++i) sq += double(t.value(i)) * t.value(i);
               return sq;
             }()},
            {"transfer_seconds", b.prepared.transfer.result.stats.seconds_total},
            {"transfer_cache_hit", b.prepared.transfer.cache_hit},
            {"transfer_key", b.prepared.transfer.key.hex()}};

  for (const auto& e : spec.environments)
    b.lights.push_back({e.name, environment_cubemap(e, desc.cubemap_resolution)});
  if (spec.fps)
    for (int i = 0; i < spec.fps_frames; ++i)
      b.fps_lights.push_back(environment_cubemap(spec.environments.front(), desc.cubemap_resolution,
                                                 360.0 * i / spec.fps_frames));
  if (!spec.images && !spec.fps) return b;

  b.scene = build_scene(desc);
  if (b.scene.mesh.positions.size() != t.vertex_count())
    throw Error(
        fmt::format("scene '{}': the built mesh has {} vertices but its cached transfer "
                    "has {} (stale stage cache? rerun with --recompute)",
                    desc.name, b.scene.mesh.positions.size(), t.vertex_count()));
  BtfParams btf;
  btf.resolution = spec.btf_resolution;
  btf.view_side = spec.btf_view_side;
  b.materials = load_scene_materials(desc, btf, cache, "full", {}, o.show_progress);
  const std::vector<std::string> views =
      spec.views.empty() ? std::vector<std::string>{""} : spec.views;
  CameraOverrides size;
  size.width = spec.width;
  size.height = spec.height;
  for (const auto& v : views) {
    b.view_names.push_back(scene_view(desc, v).name);
    b.cameras.push_back(scene_camera(b.scene, v, size));
  }
  if (!spec.images) return b;

  const auto& entry = CompressorRegistry::instance().get(spec.reference);
  CompressionResult ref =
      compress_cached(spec.reference, {}, b.prepared.input(entry), b.prepared.transfer.key, cache,
                      o.cache_mode, o.show_progress);
  FrameRenderer r(b.scene.mesh, b.materials,
                  std::shared_ptr<const CompressedTransfer>(std::move(ref.compressed)), o.device);
  for (const auto& cam : b.cameras) {
    r.set_camera(cam);
    b.masks.push_back(hit_mask(r.gbuffer()));
    for (const auto& light : b.lights) {
      r.set_environment(light.radiance);
      (void)r.render();
      b.exact_images.push_back(r.image());
      b.exposure.push_back(exposure_of(b.exact_images.back(), b.masks.back()));
    }
  }
  return b;
}

}  // namespace prt::experiments
