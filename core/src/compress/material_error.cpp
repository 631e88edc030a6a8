#include "prtlab/compress/material_error.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/base/relative_error.h"

namespace prt {

MaterialError material_error(const CompressedMaterial& material, const Btf& full) {
  const MaterialSampling s = material.sampling();
  const MaterialSampling f = sampling_of(full);
  if (s.resolution != f.resolution || s.view_side != f.view_side || s.light_side != f.light_side)
    throw ParameterError(fmt::format(
        "material error: material '{}' samples {} x {} texels, {} views, {} lights; the BTF "
        "'{}' {} x {}, {}, {}",
        material.backend(), s.resolution, s.resolution, s.view_count(), s.light_count(),
        full.material(), f.resolution, f.resolution, f.view_count(), f.light_count()));
  struct Partial {
    double diff2 = 0, ref2 = 0, max_abs = 0;
  };
  std::vector<Partial> per_texel(static_cast<std::size_t>(full.texel_count()));
  tbb::parallel_for(0, full.texel_count(), [&](int t) {
    Partial p;
    for (int v = 0; v < full.view_count(); ++v) {
      for (int j = 0; j < full.light_count(); ++j) {
        const Rgb a = material.reflectance(t, v, j), b = full.value(t, v, j);
        for (int c = 0; c < 3; ++c) {
          const double d = static_cast<double>(a[c]) - b[c];
          p.diff2 += d * d;
          p.ref2 += static_cast<double>(b[c]) * b[c];
          p.max_abs = std::max(p.max_abs, std::abs(d));
        }
      }
    }
    per_texel[static_cast<std::size_t>(t)] = p;
  });
  Partial sum;
  for (const auto& p : per_texel) {
    sum.diff2 += p.diff2;
    sum.ref2 += p.ref2;
    sum.max_abs = std::max(sum.max_abs, p.max_abs);
  }
  MaterialError e;
  e.reference_l2 = std::sqrt(sum.ref2);
  e.relative_l2 = relative_to(std::sqrt(sum.diff2), e.reference_l2,
                              "relative L2 error of material '" + material.backend() + "'");
  e.max_abs = sum.max_abs;
  e.samples = static_cast<std::uint64_t>(full.value_count());
  return e;
}

}  // namespace prt
