#include "prtlab/compress/material_compressor.h"

#include <vector>

#include "prtlab/base/error.h"

namespace prt {

MaterialSampling sampling_of(const Btf& btf) {
  return {btf.material(), btf.resolution(), btf.view_side(), btf.light_side()};
}

Rgb CompressedMaterial::shade(Vec2 uv, Vec3 view_local, std::span<const Rgb> light,
                              TexelFilter filter) const {
  const auto dim = static_cast<std::size_t>(light_basis().dim);
  PRT_CHECK(light.size() == dim, "{}: need {} light values, got {}", backend(), dim, light.size());
  std::vector<Rgb> b(dim);
  eval_lights(uv, view_local, b, filter);
  Rgb sum(0.0f);
  for (std::size_t j = 0; j < dim; ++j) sum += b[j] * light[j];
  return sum;
}

}  // namespace prt
