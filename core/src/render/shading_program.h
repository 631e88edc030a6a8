#pragma once
// The OpenCL program that shades with a material: kernels/btf_lookup.cl, the material's source
// (the material contract of compress/material_compressor.h), then kernels/btf_shading.cl, built
// with PRT_M, PRT_BILINEAR, PRT_WG_SIZE and the material's own defines.
#include <cstddef>

#include "prtlab/btf/btf.h"
#include "prtlab/compress/material_compressor.h"
#include "prtlab/opencl/cl_include.h"
#include "prtlab/render/btf_shading.h"

namespace prt {

class ClContext;

inline constexpr std::size_t kShadingWorkGroup = 64;
/// Arguments btf_shade_single and btf_view_cache take before PRT_MATERIAL_PARAMS.
inline constexpr unsigned kSingleMaterialArg = 9;
inline constexpr unsigned kViewCacheMaterialArg = 5;
inline constexpr unsigned kViewCacheShadeMaterialArg = 11;

/// `m`: values per vertex of the light basis (PRT_M). Cached like every program. `probe`
/// (benchmarks only) defines PRT_PROBE_* for btf_view_cache_shade.
cl::Program build_shading_program(ClContext& context, const DeviceMaterial& material, int m,
                                  TexelFilter filter, ShadingProbe probe = ShadingProbe::kNone);

}  // namespace prt
