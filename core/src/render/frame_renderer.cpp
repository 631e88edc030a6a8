#include "prtlab/render/frame_renderer.h"

#include <chrono>
#include <cmath>
#include <map>

#include "prtlab/base/error.h"
#include "prtlab/base/statistics.h"
#include "prtlab/btf/scene_btfs.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/light_options.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/opencl/cl_buffer.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/render/device_radiance_to_bins.h"
#include "prtlab/render/visible_vertices.h"
#include "prtlab/transfer/radiance_to_bins.h"

namespace prt {
namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

struct FrameRenderer::Impl {
  Mesh mesh;
  ShadingMaterials materials;
  std::shared_ptr<const CompressedTransfer> transfer;
  ClContext* context = nullptr;
  ShadingOptions options;
  GBufferTracer tracer;
  PrimaryRays primary_rays = PrimaryRays::kRaster;
  std::unique_ptr<DeviceRelighter> relighter;
  std::optional<DeviceBtfShader> shader;
  // How L* reaches the materials (shading_light_path). kToPixelBins: a backend relighting into
  // SH, shaded with a pixel-bin material, is converted to the bins: on the device by to_bins
  // (made at the first light change, when the relight's dimension is known), in C++ by
  // to_pixel_basis.
  MaterialLightBasis basis;
  LightPath path = LightPath::kDirect;
  std::optional<HemisphereGrid> grid;
  std::optional<DeviceRadianceToBins> to_bins;

  GBuffer gbuffer;
  // On the device path L* stays on the device (the shader reads the relighter's output buffer)
  // and is read back only when radiance() asks for it.
  mutable LocalRadiance radiance;
  mutable bool radiance_on_host = false;
  std::optional<Cubemap> environment;
  std::optional<Cubemap> background;  // what misses show; the lighting cubemap by default
  bool have_camera = false;
  RgbImage image;  // C++ path
  bool rendered = false;
  FrameStageTimes pending;
  FrameCounters counters;
  std::uint64_t pending_relit = 0;

  // Culling. A vertex is current when the current light has reached it: relit_gen[v] (or
  // all_gen, after a full relight) equals light_gen.
  bool cull = true;
  std::vector<std::uint32_t> visible;
  std::optional<LightCoeffs> light;
  std::map<std::string, std::string> light_options;  // the backend's light_params
  std::uint64_t light_gen = 0, all_gen = 0;
  std::vector<std::uint64_t> relit_gen;
  LocalRadiance relit;  // C++ path with kToPixelBins: L* in the backend's basis, kept

  bool subset_capable() const {
    if (relighter) return path == LightPath::kDirect && relighter->supports_vertex_subset();
    return transfer->supports_vertex_subset();
  }
  bool culls() const { return cull && subset_capable(); }
  bool current(std::uint32_t v) const { return all_gen == light_gen || relit_gen[v] == light_gen; }

  // Relights every vertex with `light`.
  void relight_all();
  // Relights `vertices` (sorted, unique) with `light`; the device's subset is `vertices` after.
  void relight_subset(const std::vector<std::uint32_t>& vertices);
  void check_radiance() const;

  Impl(Mesh m, ShadingMaterials mat, std::shared_ptr<const CompressedTransfer> t, ClContext* c,
       const ShadingOptions& o)
      : mesh(std::move(m)),
        materials(std::move(mat)),
        transfer(std::move(t)),
        context(c),
        options(o),
        tracer(mesh) {}
};

void FrameRenderer::Impl::check_radiance() const {
  check_light_basis(basis, radiance, mesh.positions.size(),
                    fmt::format("frame renderer: backend '{}'", transfer->backend()));
}

void FrameRenderer::Impl::relight_all() {
  if (relighter && path == LightPath::kDirect) {
    // The shader reads L* where the relight left it: no read-back, no upload.
    pending.relight_kernel_ms += relighter->relight_on_device(*light);
    radiance_on_host = false;
  } else if (relighter) {
    if (!to_bins) {
      // The first light change reads the relight back once: its dimension sizes the converter.
      LocalRadiance first;
      pending.relight_kernel_ms += relighter->relight(*light, first);
      if (first.vertices != mesh.positions.size())
        throw ParameterError(
            fmt::format("frame renderer: backend '{}' relit {} vertices; the mesh has {}",
                        transfer->backend(), first.vertices, mesh.positions.size()));
      to_bins.emplace(*context, *grid, first.dim, first.vertices);
    } else {
      pending.relight_kernel_ms += relighter->relight_on_device(*light);
    }
    pending.relight_kernel_ms += to_bins->run(relighter->output_buffer());
    radiance_on_host = false;
  } else if (path == LightPath::kToPixelBins) {
    transfer->relight(*light, relit);
    radiance = to_pixel_basis(relit, *grid);
    radiance_on_host = true;
    check_radiance();
  } else {
    transfer->relight(*light, radiance);
    radiance_on_host = true;
    check_radiance();
  }
  all_gen = light_gen;
  pending_relit += mesh.positions.size();
  counters.relit_vertices += mesh.positions.size();
}

void FrameRenderer::Impl::relight_subset(const std::vector<std::uint32_t>& vertices) {
  if (relighter) {
    relighter->set_vertex_subset(vertices);
    pending.relight_kernel_ms += relighter->relight_subset_on_device(*light);
    radiance_on_host = false;
  } else if (path == LightPath::kToPixelBins) {
    transfer->relight_vertices(*light, vertices, relit);
    radiance = to_pixel_basis(relit, *grid);
    radiance_on_host = true;
    check_radiance();
  } else {
    transfer->relight_vertices(*light, vertices, radiance);
    radiance_on_host = true;
    check_radiance();
  }
  for (const std::uint32_t v : vertices) relit_gen[v] = light_gen;
  pending_relit += vertices.size();
  counters.relit_vertices += vertices.size();
}

FrameRenderer::FrameRenderer(Mesh mesh, ShadingMaterials materials,
                             std::shared_ptr<const CompressedTransfer> transfer, ClContext* context,
                             const ShadingOptions& options,
                             const std::map<std::string, std::string>& device_options,
                             const std::map<std::string, std::string>& material_device_options) {
  if (!transfer) throw ParameterError("frame renderer: no compressed transfer given");
  if (materials.part_material.empty() || !materials.part_material.front())
    throw ParameterError("frame renderer: no materials given");
  const MaterialLightBasis basis = validate_materials(materials, mesh);
  const LightPath path = shading_light_path(transfer->output_basis(), basis, transfer->backend(),
                                            materials.part_material.front()->backend());
  impl_ = std::make_unique<Impl>(std::move(mesh), std::move(materials), std::move(transfer),
                                 context, options);
  Impl& s = *impl_;
  s.basis = basis;
  s.path = path;
  s.relit_gen.assign(s.mesh.positions.size(), 0);
  if (s.path == LightPath::kToPixelBins) {
    const int side = static_cast<int>(std::lround(std::sqrt(s.basis.dim)));
    if (side * side != s.basis.dim)
      throw ParameterError(fmt::format("frame renderer: M = {} is no square grid", s.basis.dim));
    s.grid.emplace(side);
  }
  if (context) {
    s.relighter = upload_compressed(*s.transfer, *context, device_options);
    if (!s.relighter)
      throw ParameterError(
          fmt::format("frame renderer: backend '{}' has no OpenCL relight (run "
                      "with --no-opencl for the C++ path)",
                      s.transfer->backend()));
    s.shader.emplace(*context, s.mesh, s.materials, nullptr, options, material_device_options);
    // Checks the buffer's size against the mesh before the first frame.
    if (s.path == LightPath::kDirect) s.shader->set_radiance_buffer(s.relighter->output_buffer());
  }
}

FrameRenderer::~FrameRenderer() = default;
FrameRenderer::FrameRenderer(FrameRenderer&&) noexcept = default;
FrameRenderer& FrameRenderer::operator=(FrameRenderer&&) noexcept = default;

void FrameRenderer::set_camera(const Camera& camera) {
  Impl& s = *impl_;
  auto t0 = Clock::now();
  s.tracer.trace(camera, s.gbuffer, s.primary_rays);
  s.pending.gbuffer_ms += ms_since(t0);
  if (s.shader) {
    t0 = Clock::now();
    s.shader->set_gbuffer(s.gbuffer);
    s.pending.gbuffer_upload_ms += ms_since(t0);
  }
  s.have_camera = true;
  ++s.counters.gbuffer_traces;

  t0 = Clock::now();
  s.visible = prt::visible_vertices(s.gbuffer, s.mesh);
  std::vector<std::uint32_t> missing;
  if (s.light) {
    for (const std::uint32_t v : s.visible)
      if (!s.current(v)) missing.push_back(v);
  }
  s.pending.cull_ms += ms_since(t0);
  if (!missing.empty()) {
    // Only a culled light change leaves vertices behind, so the backend relights subsets.
    t0 = Clock::now();
    s.relight_subset(missing);
    s.pending.relight_ms += ms_since(t0);
  }
  if (s.relighter && s.culls()) {
    t0 = Clock::now();
    s.relighter->set_vertex_subset(s.visible);
    s.pending.cull_ms += ms_since(t0);
  }
}

void FrameRenderer::set_light_options(const std::map<std::string, std::string>& options) {
  (void)CompressorRegistry::instance().light_options(impl_->transfer->backend(), options);
  impl_->light_options = options;
}

void FrameRenderer::set_environment(const Cubemap& environment, const Cubemap* background) {
  Impl& s = *impl_;
  auto t0 = Clock::now();
  s.light = project_light_with(*s.transfer, environment, s.light_options);
  ++s.light_gen;
  s.pending.project_ms += ms_since(t0);
  t0 = Clock::now();
  if (s.have_camera && s.culls()) {
    // The device's subset is already the visible set (set_camera uploaded it).
    if (s.relighter) {
      s.pending.relight_kernel_ms += s.relighter->relight_subset_on_device(*s.light);
      s.radiance_on_host = false;
      for (const std::uint32_t v : s.visible) s.relit_gen[v] = s.light_gen;
      s.pending_relit += s.visible.size();
      s.counters.relit_vertices += s.visible.size();
    } else {
      s.relight_subset(s.visible);
    }
  } else {
    s.relight_all();
  }
  s.pending.relight_ms += ms_since(t0);
  s.environment.emplace(environment);
  s.background.emplace(background ? *background : environment);
  if (s.shader) {
    t0 = Clock::now();
    s.shader->set_radiance_buffer(s.to_bins ? s.to_bins->output_buffer()
                                            : s.relighter->output_buffer());
    s.shader->set_background(&*s.background);
    s.pending.upload_ms += ms_since(t0);
  }
  ++s.counters.relights;
}

void FrameRenderer::set_primary_rays(PrimaryRays rays) {
  impl_->primary_rays = rays;
}

void FrameRenderer::set_culling(bool on) {
  Impl& s = *impl_;
  if (on && !s.cull && s.relighter && s.culls() && s.have_camera)
    s.relighter->set_vertex_subset(s.visible);
  s.cull = on;
}
bool FrameRenderer::culling() const {
  return impl_->cull;
}
bool FrameRenderer::culls() const {
  return impl_->culls();
}
const std::vector<std::uint32_t>& FrameRenderer::visible_vertices() const {
  return impl_->visible;
}

FrameStats FrameRenderer::render() {
  Impl& s = *impl_;
  if (!s.have_camera || !s.environment)
    throw ParameterError("frame renderer: set_camera and set_environment must precede render()");
  const auto t0 = Clock::now();
  if (s.shader) {
    s.pending.shade_kernel_ms = s.shader->shade();
    s.pending.view_cache_kernel_ms = s.shader->last_view_cache_ms();
  } else {
    s.image = shade_frame_reference(s.gbuffer, s.mesh, s.materials, s.radiance, &*s.background,
                                    s.options);
  }
  s.pending.shade_ms = ms_since(t0);
  s.rendered = true;
  ++s.counters.frames;
  FrameStats stats{s.pending, s.counters, s.pending_relit, s.visible.size()};
  s.pending = {};
  s.pending_relit = 0;
  return stats;
}

RgbImage FrameRenderer::image() const {
  const Impl& s = *impl_;
  if (!s.rendered) throw ParameterError("frame renderer: nothing rendered yet");
  return s.shader ? s.shader->read_image() : s.image;
}

bool FrameRenderer::uses_opencl() const {
  return impl_->shader.has_value();
}
const FrameCounters& FrameRenderer::counters() const {
  return impl_->counters;
}
const Mesh& FrameRenderer::mesh() const {
  return impl_->mesh;
}
const GBuffer& FrameRenderer::gbuffer() const {
  return impl_->gbuffer;
}
const LocalRadiance& FrameRenderer::radiance() const {
  const Impl& s = *impl_;
  if (!s.radiance_on_host && s.relighter && s.environment) {
    s.radiance = LocalRadiance(s.basis.basis, s.basis.dim, s.mesh.positions.size());
    if (!s.radiance.values.empty())
      download(*s.context, s.to_bins ? s.to_bins->output_buffer() : s.relighter->output_buffer(),
               std::span<Rgb>(s.radiance.values), "frame renderer local radiance");
    s.radiance_on_host = true;
  }
  return s.radiance;
}
const DeviceBtfShader* FrameRenderer::device_shader() const {
  return impl_->shader ? &*impl_->shader : nullptr;
}

// ---- helpers -------------------------------------------------------------------------------

ShadingMaterials load_scene_materials(const SceneDesc& desc, BtfParams params, StageCache& cache,
                                      const std::string& material,
                                      const std::map<std::string, std::string>& material_params,
                                      bool show_progress, int* cache_hits) {
  const auto btfs = scene_part_btfs(desc, params, cache, show_progress, cache_hits);
  return {compress_part_materials(btfs, material, material_params)};
}

LatLongImage rotate_latlong_y(const LatLongImage& image, double degrees) {
  LatLongImage out = image;
  const int w = image.width;
  if (w <= 0) return out;
  // Rotating by alpha maps phi to phi - alpha, so the new column c samples the old image at
  // c + alpha W / 2 pi.
  double shift = degrees / 360.0 * w;
  shift -= std::floor(shift / w) * w;  // [0, W)
  const int whole = static_cast<int>(std::floor(shift));
  const float frac = static_cast<float>(shift - whole);
  for (int row = 0; row < image.height; ++row) {
    for (int c = 0; c < w; ++c) {
      const int c0 = (c + whole) % w, c1 = (c + whole + 1) % w;
      out.texels[static_cast<std::size_t>(row) * w + c] =
          (1.0f - frac) * image.at(c0, row) + frac * image.at(c1, row);
    }
  }
  return out;
}

Camera orbit_camera(const Camera& camera, double degrees) {
  const double a = degrees * kPi / 180.0;
  const double c = std::cos(a), s = std::sin(a);
  const Vec3d r = camera.eye - camera.target;
  Camera out = camera;
  out.eye = camera.target + Vec3d(r.x * c + r.z * s, r.y, -r.x * s + r.z * c);
  return out;
}

}  // namespace prt
