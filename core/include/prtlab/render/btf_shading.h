#pragma once
// Per-pixel bi-scale shading (the central paper's eq. 3; DESIGN.md "Conventions"):
//
//   B(x, e) = sum_j b(u(x), e(x), d_j) * L*_j(x),   L*(x) = sum_i beta_i L*_{p_i}
//
// where p_0..p_2 are the vertices of the triangle hit at pixel x, beta their barycentrics (from
// the G-buffer), L*_p the vertex's local incident radiance in the material's light basis (the M
// pixel bins for a pixel-bin material: the output of relight()), and b the reflectance vector
// of the triangle's part's material (any CompressedMaterial, compress/material_compressor.h;
// for the `full` material the BTF interpolated between the 4 nearest view samples on the
// sphere, btf_view_samples) at the pixel's UV and view.
// Pixels that miss the mesh show the environment radiance in the ray direction (when a
// background is given) or black.
//
// Two implementations: shade_frame_reference (C++, CompressedMaterial::shade, the reference) and
// DeviceBtfShader (the OpenCL kernels kernels/btf_shading.cl with the material's source, the
// material contract). tests/core/btf_shading_test.cpp compares them.
//
// Background: a miss shows the radiance of the background cubemap pixel containing the ray
// direction, CubemapLayout::pixel_of(G-buffer direction) in double on the host (both paths use
// the same index, so a direction on a pixel edge cannot pick different pixels in the two).
//
// View cache (DeviceBtfShader, ShadingOptions::cache_view_vectors, on by default): the
// view-interpolated BTF vector b(u(x), e(x), .) (M RGB values) of every hit pixel depends on
// the view only. It is computed once per G-buffer (a "view-cache" kernel reading the 4 view
// samples, 1 for a view-independent BTF, x 1 or 4 texels) and kept on the device; every shading
// pass then reads M RGB values of b per pixel instead of 4 (nearest) or 16 (bilinear) times as
// many: a light change only does the dot products. The first pass after a new G-buffer builds
// the cache and shades the hit pixels in one kernel (btf_view_cache_shade: the dot product is
// taken on the values as they are stored, so the image is the one the cached pass gives), then
// copies the misses' background. Without the cache, one kernel interpolates and dots in one
// pass. docs/rendering.md "BTF shading" has the measurements.
#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace cl {
class Buffer;
}

#include "prtlab/btf/btf.h"
#include "prtlab/compress/material_compressor.h"
#include "prtlab/geometry/mesh.h"
#include "prtlab/image/image_io.h"
#include "prtlab/render/gbuffer.h"
#include "prtlab/sphere/cubemap.h"
#include "prtlab/transfer/local_radiance.h"

namespace prt {

class ClContext;

/// What a benchmark leaves out of the view-change kernel (ShadingOptions::probe): the material's
/// vector reads (its weights stand in for the vectors), the cache writes, the view samples (a
/// fixed pattern of views stands in for prt_view_samples), or everything but one read and one
/// write per hit pixel (the launch alone).
enum class ShadingProbe { kNone, kNoVectorReads, kNoCacheWrites, kFixedViews, kLaunchOnly };

struct ShadingOptions {
  TexelFilter filter = TexelFilter::kNearest;
  bool background = true;  ///< misses show the environment (needs a background cubemap)
  /// DeviceBtfShader only: keep b(u, e) per hit pixel on the device between light changes
  /// (see the file comment), unless no part's material gains from it
  /// (DeviceMaterial::view_cache_useful: every part a view-independent `full` BTF with nearest
  /// texels). The image is the same either way (to float rounding).
  bool cache_view_vectors = true;
  /// For benchmarks only: a part of the view-change kernel (btf_view_cache_shade) left out, to
  /// measure what each part costs. Any value but kNone makes the image wrong.
  ShadingProbe probe = ShadingProbe::kNone;
};

/// The materials of a scene for shading: one compressed material per part (index = part id of
/// the mesh's triangle_part; compress_part_materials in compress/material_registry.h builds
/// them from the parts' BTFs). Parts may share a material. All parts use one material backend
/// and one light basis, which the local radiance must be in.
struct ShadingMaterials {
  std::vector<std::shared_ptr<const CompressedMaterial>> part_material;
  std::vector<const CompressedMaterial*> parts() const;
};

/// Throws ParameterError unless every part of `mesh` has a material (non-null), all of one
/// backend and one light basis; returns that basis.
MaterialLightBasis validate_materials(const ShadingMaterials& materials, const Mesh& mesh);

/// C++ reference of the shading pass: width x height radiance image. `radiance` must be in
/// the materials' light basis with one block of dim values per mesh vertex. Parallel over rows
/// (TBB). Hit pixels: L*(x) interpolated in float (b0 = 1 - b1 - b2), then
/// CompressedMaterial::shade.
RgbImage shade_frame_reference(const GBuffer& gbuffer, const Mesh& mesh,
                               const ShadingMaterials& materials, const LocalRadiance& radiance,
                               const Cubemap* background, const ShadingOptions& options = {});

/// The OpenCL shading pass. The mesh's triangles and the materials are uploaded once
/// (upload_materials, with `material_device_options`); the G-buffer
/// on a view change (set_gbuffer); L* on a light change (set_radiance), the background with
/// it (set_background). shade() runs the kernel(s) and leaves the image on the device;
/// read_image() reads it back.
///
/// Device data: the materials' buffers (DeviceMaterial); the G-buffer compacted to its hit pixels
/// ("slots": triangle, part, barycentrics, UV, local view) plus one int per pixel (slot, or the
/// background pixel of a miss); L* as uploaded (vertices x M x RGB floats); the image as width x
/// height x RGB floats.
class DeviceBtfShader {
 public:
  DeviceBtfShader(ClContext& context, const Mesh& mesh, const ShadingMaterials& materials,
                  const Cubemap* background, const ShadingOptions& options = {},
                  const std::map<std::string, std::string>& material_device_options = {});
  ~DeviceBtfShader();
  DeviceBtfShader(DeviceBtfShader&&) noexcept;
  DeviceBtfShader& operator=(DeviceBtfShader&&) noexcept;

  void set_gbuffer(const GBuffer& gbuffer);
  void set_radiance(const LocalRadiance& radiance);
  /// Shade from L* already on the device (a DeviceRelighter's output_buffer(): vertices x M x
  /// RGB floats, same context): no copy. The buffer must stay alive and is read at each
  /// shade(). ParameterError when it is too small for the mesh.
  void set_radiance_buffer(const cl::Buffer& radiance);
  /// A new background (the environment of a light change); nullptr: black. Its resolution
  /// may differ from the previous one's.
  void set_background(const Cubemap* background);
  /// Kernel milliseconds (OpenCL profiling) of one shading pass, including the view-cache
  /// kernel when the G-buffer changed since the last pass.
  double shade();
  /// Kernel milliseconds of the view-cache kernel in the last shade(), which also shades the hit
  /// pixels (0 when it did not run).
  double last_view_cache_ms() const;
  /// Whether shade() runs the cached kernels: ShadingOptions::cache_view_vectors and some part's
  /// material gains from the cache; else the single-pass kernel.
  bool uses_view_cache() const;
  RgbImage read_image() const;

  /// Bytes of material and L* data the kernel reads for the current G-buffer (each hit pixel:
  /// DeviceMaterial::bytes_per_hit, for `full` 4 view samples x M x RGB floats of its texel(s);
  /// 3 vertices x M x RGB floats of L*), the
  /// numerator of the bandwidth bound. This is the single-pass (uncached) shading kernel's
  /// traffic; bytes_per_pass() splits the cached passes.
  std::uint64_t bytes_read_per_frame() const;
  /// Bytes each kind of pass moves for the current G-buffer (reads + the cache write).
  struct PassBytes {
    std::uint64_t single_pass = 0;  ///< == bytes_read_per_frame()
    std::uint64_t view_cache =
        0;  ///< material reads of the view-cache kernel + its cache writes (it also
            ///< reads 3 vertices' L* to shade the hits: not counted)
    std::uint64_t cached_shade = 0;  ///< b(u, e) + 3 vertices' L* per hit pixel
  };
  PassBytes bytes_per_pass() const;
  std::size_t hit_pixels() const;
  std::uint64_t device_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace prt
