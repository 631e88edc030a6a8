#pragma once
// The frame loop of bi-scale PRT (DESIGN.md "Data flow"; docs/rendering.md "Frame loop"):
//
//   view change  (set_camera)       trace the G-buffer (Embree), upload it; L* is reused
//   light change (set_environment)  project the light into the backend's basis, relight (on
//                                   the device, the shader reads L* where the relight wrote
//                                   it), upload the environment as the background
//   render()                        shade the current G-buffer with the current L*
//
// Culling (docs/rendering.md, "Culling"; on by default, set_culling): a frame reads L* only at
// the vertices of its hit triangles (visible_vertices.h), so when the backend can relight a
// vertex subset (CompressedTransfer / DeviceRelighter::supports_vertex_subset) a light change
// relights only those, and a view change relights the newly visible vertices that the current
// light has not reached yet. The image is bit-identical to the unculled one.
//
// A FrameRenderer holds the scene's mesh, its materials, one compressed transfer (any backend,
// through the core interface only), the backend's DeviceRelighter and a DeviceBtfShader when
// an OpenCL context is given, else the C++ relight and shade_frame_reference, and a
// GBufferTracer. render() returns the wall-clock milliseconds of every stage run since the
// previous render() and the running counters, so callers (prtlab fps, tests) can see that a
// view-only change did not relight.
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "prtlab/btf/btf_generator.h"
#include "prtlab/compress/compressor.h"
#include "prtlab/geometry/camera.h"
#include "prtlab/geometry/scene.h"
#include "prtlab/lighting/environment_map.h"
#include "prtlab/render/btf_shading.h"
#include "prtlab/render/gbuffer.h"
#include "prtlab/storage/stage_cache.h"

namespace prt {

class ClContext;

/// Wall-clock milliseconds of the stages of one frame (those not run are 0).
struct FrameStageTimes {
  double gbuffer_ms = 0;         ///< view change: the G-buffer (rasterised, or primary rays)
  double gbuffer_upload_ms = 0;  ///< view change: G-buffer compaction + upload (device path)
  double project_ms = 0;         ///< light change: CompressedTransfer::project_light
  double relight_ms = 0;         ///< light change: relight (device: light upload and kernels)
  double upload_ms = 0;          ///< light change: background upload to the shader (device path)
  double shade_ms = 0;           ///< shading pass, waited for (device: kernels; C++: the reference)
  /// Device time of the shading kernels (OpenCL profiling; 0 on the C++ path), and the part of
  /// it spent building the view cache (0 unless the G-buffer changed).
  double shade_kernel_ms = 0;
  double view_cache_kernel_ms = 0;
  double relight_kernel_ms = 0;  ///< device time of the relight kernels (0 on the C++ path)
  /// View change: the visible vertex set and its upload to the relighter (culling only; the
  /// relight of newly visible vertices counts as relight_ms).
  double cull_ms = 0;

  /// Sum of the wall-clock stages: the frame time.
  double total_ms() const {
    return gbuffer_ms + gbuffer_upload_ms + cull_ms + project_ms + relight_ms + upload_ms +
           shade_ms;
  }
};

/// Running totals since construction.
struct FrameCounters {
  std::uint64_t frames = 0;          ///< render() calls
  std::uint64_t gbuffer_traces = 0;  ///< set_camera() calls
  std::uint64_t relights = 0;        ///< set_environment() calls (each relights once)
  /// Vertices relit (every vertex of a full relight, the subset of a culled one, the newly
  /// visible ones of a view change).
  std::uint64_t relit_vertices = 0;
};

struct FrameStats {
  FrameStageTimes times;  ///< of the stages run since the previous render()
  FrameCounters counters;
  std::uint64_t relit_vertices = 0;    ///< vertices relit since the previous render()
  std::uint64_t visible_vertices = 0;  ///< vertices of the current view's hit triangles
};

class FrameRenderer {
 public:
  /// `context` null: C++ relight and shading. L* reaches the materials as shading_light_path()
  /// says (compress/material_light_basis.h): directly when the transfer's output basis is the
  /// materials' light basis; a transfer relighting into SH shaded with pixel-bin materials is
  /// evaluated at the bins (to_pixel_basis; on the device, DeviceRadianceToBins). Throws
  /// ParameterError when there is no such path, when the transfer's vertex count differs from
  /// the mesh's or a material does not match (validate_materials).
  /// `device_options`: the backend's device_params for its upload; `material_device_options`
  /// the material backend's, for the shader's.
  FrameRenderer(Mesh mesh, ShadingMaterials materials,
                std::shared_ptr<const CompressedTransfer> transfer, ClContext* context,
                const ShadingOptions& options = {},
                const std::map<std::string, std::string>& device_options = {},
                const std::map<std::string, std::string>& material_device_options = {});
  ~FrameRenderer();
  FrameRenderer(FrameRenderer&&) noexcept;
  FrameRenderer& operator=(FrameRenderer&&) noexcept;

  /// View change: trace and upload the G-buffer. L* is kept.
  void set_camera(const Camera& camera);
  /// Light change: project, relight (on the device path the shader then reads L* from the
  /// relighter's output buffer: nothing crosses to the host), upload the background. `background`,
  /// when given, is what misses show (e.g. a finer cubemap of the same environment); without it
  /// misses show the lighting cubemap itself.
  void set_environment(const Cubemap& environment, const Cubemap* background = nullptr);
  /// The backend's light_params (light_options.h) for every later light change (validated:
  /// ParameterError listing them). Does not relight by itself.
  void set_light_options(const std::map<std::string, std::string>& options);
  /// How set_camera finds what each pixel sees (rasterised by default, packets when a vertex
  /// lies at or behind the eye's plane; kSingle is the reference path).
  void set_primary_rays(PrimaryRays rays);
  /// Culling on (the default) or off. Off, every light change relights every vertex; either
  /// way a view change relights the visible vertices the current light has not reached, so L*
  /// is never stale where the frame reads it.
  void set_culling(bool on);
  bool culling() const;
  /// Whether light changes are culled: culling() and the backend relights vertex subsets on
  /// this path (device: and its L* is shaded directly, not converted to bins).
  bool culls() const;
  /// The vertices of the current view's hit triangles, sorted (visible_vertices.h).
  const std::vector<std::uint32_t>& visible_vertices() const;

  /// Shade (needs a camera and an environment: ParameterError otherwise).
  FrameStats render();
  /// The last rendered image (read back from the device on the OpenCL path).
  RgbImage image() const;

  bool uses_opencl() const;
  const FrameCounters& counters() const;
  const Mesh& mesh() const;
  const GBuffer& gbuffer() const;  ///< of the current camera
  /// L* of the current environment in the materials' light basis (on the device path read back
  /// on the first call after a light change). With culling, only the rows of vertices relit
  /// for the current light (at least the visible ones) are current; others may hold an earlier
  /// light's values (or zeros).
  const LocalRadiance& radiance() const;
  /// The device shader (nullptr on the C++ path): byte counts, hit pixels.
  const DeviceBtfShader* device_shader() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// ---- helpers of the render and fps commands ------------------------------------------------

/// The material of every part of a scene: the part BTFs (scene_part_btfs: generate_btf_cached
/// with light_side = desc.local_grid, once per distinct BTF) compressed with the material
/// backend `material` ("full" keeps them as they are) and `material_params`.
/// `cache_hits` (optional) counts the BTFs that came from the stage cache.
ShadingMaterials load_scene_materials(const SceneDesc& desc, BtfParams params, StageCache& cache,
                                      const std::string& material,
                                      const std::map<std::string, std::string>& material_params,
                                      bool show_progress = false, int* cache_hits = nullptr);

/// The environment rotated by `degrees` about +y (right-handed: +x turns towards -z):
/// L'(d) = L(R^-1 d). A lat-long image rotates about +y by a shift of its columns; fractional
/// shifts interpolate linearly between the two nearest columns (power is kept exactly, since
/// every row's texels have the same solid angle).
LatLongImage rotate_latlong_y(const LatLongImage& image, double degrees);

/// `camera` with its eye turned by `degrees` about the vertical (+y) axis through its target
/// (an orbit; up, field of view and size kept).
Camera orbit_camera(const Camera& camera, double degrees);

}  // namespace prt
