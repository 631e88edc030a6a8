#pragma once
// A material against the full BTF it represents, over every sample: all texels, view samples,
// light bins and colour channels, through CompressedMaterial::reflectance only (so any light
// basis is measured at the bins, in the full BTF's units).
#include <cstdint>

#include "prtlab/btf/btf.h"
#include "prtlab/compress/material_compressor.h"

namespace prt {

struct MaterialError {
  /// sqrt(sum (b~ - b)^2) / sqrt(sum b^2); NaN if b = 0 (base/relative_error.h)
  double relative_l2 = 0;
  double max_abs = 0;         ///< largest |b~ - b|
  double reference_l2 = 0;    ///< sqrt(sum b^2)
  std::uint64_t samples = 0;  ///< values compared (texels x views x lights x 3)
};

/// ParameterError when the material's sampling differs from the BTF's. Sums in double,
/// parallel over texels with a fixed reduction order (the result does not depend on threads).
MaterialError material_error(const CompressedMaterial& material, const Btf& full);

}  // namespace prt
