#pragma once
// A material's reflectance vectors b(uv, e, .) computed on the device by the shading program's
// view-cache kernel (kernels/btf_shading.cl), i.e. by the material's OpenCL source exactly as
// shading runs it: the OpenCL side that the material conformance suite compares with
// CompressedMaterial::eval_lights.
#include <map>
#include <span>
#include <string>
#include <vector>

#include "prtlab/base/types.h"
#include "prtlab/btf/btf.h"
#include "prtlab/compress/material_compressor.h"

namespace prt {

class ClContext;

struct MaterialQuery {
  int part = 0;  ///< index into the parts given
  Vec2 uv{0.0f};
  Vec3 view_local{0.0f, 0.0f, 1.0f};
};

/// queries.size() x light_basis().dim values, query-major. The parts go through
/// upload_materials (one backend, one light basis; ParameterError otherwise).
std::vector<Rgb> evaluate_materials_on_device(
    ClContext& context, std::span<const CompressedMaterial* const> parts,
    std::span<const MaterialQuery> queries, TexelFilter filter,
    const std::map<std::string, std::string>& device_options = {});

}  // namespace prt
