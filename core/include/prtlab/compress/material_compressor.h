#pragma once
// The material-compressor interface: the second plugin kind, beside the transfer compressors of
// compressor.h. A material backend implements:
//
//   MaterialCompressor  built by name from validated parameters (material_registry.h);
//                       compress() turns a sampled BTF (btf/btf.h) into a CompressedMaterial.
//   CompressedMaterial  what the shading pass reads: storage, FLOPs per shaded pixel, its light
//                       basis (material_light_basis.h), the reflectance in C++ (at the BTF's
//                       samples, and interpolated for shading), its OpenCL side, save.
//   DeviceMaterial      the materials of every part of one shading program on the device: an
//                       OpenCL C source implementing the material contract (below) and the
//                       buffers it reads.
//
// Every material is measured against the full BTF it came from (material_error.h).
//
// The material contract (OpenCL C 1.2; docs/adding-a-material.md has an example). The shading
// program is the prelude, kernels/btf_lookup.cl (the view and texel lookups of btf.h, usable by
// any material), the material's source, then kernels/btf_shading.cl (the kernels). The host
// defines PRT_M (the light basis' dim), PRT_BILINEAR (0 nearest, 1 bilinear texels) and
// PRT_WG_SIZE. The source defines:
//
//   PRT_MATERIAL_PARAMS  its kernel parameters, each preceded by a comma
//                        (", __global const float* restrict mat_data, ...")
//   PRT_MATERIAL_ARGS    the same names, each preceded by a comma (", mat_data, ...")
//   prt_material         a type holding what one pixel's evaluation needs
//   void prt_material_begin(prt_material* m, int part, float2 uv, float3 view
//                           PRT_MATERIAL_PARAMS)
//   void prt_material_chunk(const prt_material* m, int c, float4* b0, float4* b1, float4* b2
//                           PRT_MATERIAL_PARAMS)
//       the floats c .. c + 11 of b(u, e, .) (3 PRT_M floats, packed RGB: b[3 j + channel]),
//       c a multiple of 12 below 3 PRT_M - 11
//   float prt_material_one(const prt_material* m, int c PRT_MATERIAL_PARAMS)
//       the float c of b(u, e, .) (the 3 PRT_M % 12 tail floats)
//
// A material whose lookup interpolates view samples (prt_view_samples of btf_lookup.cl) on one
// view grid per part may also define PRT_MATERIAL_SLOT_VIEWS and
//   void prt_material_begin_views(prt_material* m, int part, float2 uv, int4 views,
//                                 float4 view_weights PRT_MATERIAL_PARAMS)
// which is prt_material_begin with those view samples given; DeviceMaterial::view_sides() then
// names each part's grid side, and the view-change kernel takes the samples from a kernel that
// computes them for 16 hit pixels a work-item in vector code.
//
// DeviceMaterial::set_args binds the PRT_MATERIAL_PARAMS after each kernel's own arguments.
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "prtlab/base/progress.h"
#include "prtlab/base/types.h"
#include "prtlab/btf/btf.h"
#include "prtlab/compress/material_light_basis.h"
#include "prtlab/compress/params.h"
#include "prtlab/compress/storage_report.h"
#include "prtlab/opencl/cl_program.h"

namespace prt {

class ArchiveWriter;
class ClContext;

/// What a material compressor sees.
struct MaterialInput {
  /// The full BTF, shared so that a representation that keeps it (full) need not copy it.
  std::shared_ptr<const Btf> btf;
};

/// The sampling of the BTF a material represents; reflectance() is defined on it.
struct MaterialSampling {
  std::string material;  ///< the BTF's material name ("checker")
  int resolution = 0;    ///< U: texels per side
  int view_side = 0;     ///< V = view_side^2 view samples
  int light_side = 0;    ///< M = light_side^2 light bins
  int texel_count() const { return resolution * resolution; }
  int view_count() const { return view_side * view_side; }
  int light_count() const { return light_side * light_side; }
  bool operator==(const MaterialSampling&) const = default;
};
MaterialSampling sampling_of(const Btf& btf);

/// The materials of all parts of one shading program, resident on an OpenCL device.
class DeviceMaterial {
 public:
  virtual ~DeviceMaterial() = default;
  /// Names source() in messages and #line markers ("full_material.cl").
  virtual std::string label() const = 0;
  /// OpenCL C 1.2 implementing the material contract (file comment).
  virtual std::string source() const = 0;
  /// Defines the source needs besides PRT_M, PRT_BILINEAR and PRT_WG_SIZE.
  virtual KernelDefines defines() const { return {}; }
  /// Binds the buffers PRT_MATERIAL_PARAMS declares, in order, from argument index `first`.
  virtual void set_args(cl::Kernel& kernel, unsigned first) const = 0;
  /// Bytes of device memory held.
  virtual std::uint64_t device_bytes() const = 0;
  /// Bytes of material data one hit pixel of `part` reads to build b(u, e, .) with `filter`:
  /// the material's share of the shading pass's bandwidth bound.
  virtual std::uint64_t bytes_per_hit(std::size_t part, TexelFilter filter) const = 0;
  /// Whether keeping b(u, e, .) of a hit pixel of `part` on the device between light changes
  /// (the shader's view cache) can save work over evaluating the material again: false only when
  /// the lookup itself is one read of the vector the cache would hold (a view-independent `full`
  /// BTF with nearest texels). The shader skips the cache when no part gains from it.
  /// The side of each part's view grid when the material's source defines
  /// PRT_MATERIAL_SLOT_VIEWS and prt_material_begin_views (the material contract, file comment):
  /// the shader then computes the view samples of every hit pixel once, 16 pixels a work-item,
  /// and hands them to prt_material_begin_views. 0 for a part whose lookup takes none. Empty
  /// (the default): prt_material_begin computes what it needs.
  virtual std::vector<int> view_sides() const { return {}; }
  virtual bool view_cache_useful(std::size_t /*part*/, TexelFilter /*filter*/) const {
    return true;
  }
};

class CompressedMaterial {
 public:
  virtual ~CompressedMaterial() = default;

  /// Registered material backend name (what load_material() dispatches on).
  virtual std::string backend() const = 0;
  virtual StorageReport storage() const = 0;
  /// FLOPs of one shaded pixel for one colour channel with nearest texels, counted as the
  /// papers count them (a multiply-add is 2): building b(u, e, .) from the representation and
  /// its dot product with L*.
  virtual double flops_per_pixel() const = 0;
  /// The relative L2 error against the full BTF over all texels, views, light bins and
  /// channels (material_error.h) that the backend guarantees; 0 for lossless (then only float
  /// rounding remains).
  virtual double declared_error_bound() const = 0;
  virtual MaterialLightBasis light_basis() const = 0;
  virtual MaterialSampling sampling() const = 0;

  /// The reflectance at a sample of the BTF: texel (y U + x), view sample, light bin j < S^2,
  /// in the units of the full BTF (btf.h: exitant radiance per unit irradiance, the cell-mean
  /// cosine included), whatever the light basis.
  virtual Rgb reflectance(int texel, int view, int light) const = 0;
  /// b(uv, e, .) in light_basis(), light_basis().dim values into `out`: the texel filter, then
  /// the view interpolation (btf_view_samples for a view-sampled material).
  virtual void eval_lights(Vec2 uv, Vec3 view_local, std::span<Rgb> out,
                           TexelFilter filter) const = 0;
  /// sum_j b(uv, e)_j L*_j per channel (`light`: light_basis().dim values). The default sums
  /// eval_lights' products in order of j.
  virtual Rgb shade(Vec2 uv, Vec3 view_local, std::span<const Rgb> light, TexelFilter filter) const;

  /// The device side of `parts`, the materials of every part of one shading program (this is
  /// one of them; upload_materials() in material_registry.h checks that all are of this
  /// backend, with one light basis). `device_options` holds the entry's device_params. The
  /// result may keep a reference to `context`, which must outlive it.
  virtual std::unique_ptr<DeviceMaterial> upload(ClContext& context,
                                                 std::span<const CompressedMaterial* const> parts,
                                                 const ParamSet& device_options) const = 0;

  /// Serialise the state (the registry writes the header and the backend name).
  virtual void save(ArchiveWriter& archive) const = 0;
};

class MaterialCompressor {
 public:
  virtual ~MaterialCompressor() = default;
  virtual std::unique_ptr<CompressedMaterial> compress(const MaterialInput& input,
                                                       Progress& progress) const = 0;
};

}  // namespace prt
