#pragma once
// The device side of a material whose b(u, e, .) is a stored table of (texel, view) vectors,
// held in a Btf whose "light" axis is the material's light basis: the sampled BTF itself
// (material `full`: light_count() = M pixel bins) or a radiance transfer texture (light_count()
// = order^2 SH coefficients over the light direction, light_side() = order). Evaluated by
// kernels/btf_table_material.cl: the texel filter and the view interpolation of btf.h, then the
// weighted sum of the table's vectors, the same sum Btf::eval_lights computes.
#include <memory>
#include <span>
#include <string>

#include "prtlab/btf/btf.h"
#include "prtlab/compress/material_compressor.h"

namespace prt {

class ClContext;

/// Every part's table in one device buffer (each distinct table once; a view-independent one
/// with its view 0 only, U^2 x dim x 3 floats) with per-part offsets and (U, view_side,
/// view_independent) tables. All tables have the same light_count(). `label` names the
/// material in messages ("full"). The context must outlive the result.
std::unique_ptr<DeviceMaterial> upload_btf_tables(ClContext& context,
                                                  std::span<const Btf* const> parts,
                                                  std::string label);

}  // namespace prt
