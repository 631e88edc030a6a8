#include "prtlab/compress/material_error.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/base/relative_error.h"
#include "prtlab/sphere/hemisphere_grid.h"

namespace prt {

namespace {

struct Partial {
  double diff2 = 0, ref2 = 0, max_abs = 0;
  double rel_sum = 0, floored_sum = 0, abs_sum = 0;
  std::uint64_t rel_count = 0, floored_count = 0, zero = 0;
  double cos_diff2 = 0, cos_ref2 = 0;
  double white_diff2 = 0, white_ref2 = 0;
};

double mean_or_nan(double sum, std::uint64_t count) {
  return count > 0 ? sum / static_cast<double>(count) : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

MaterialError material_error(const CompressedMaterial& material, const Btf& full) {
  const MaterialSampling s = material.sampling();
  const MaterialSampling f = sampling_of(full);
  if (s.resolution != f.resolution || s.view_side != f.view_side || s.light_side != f.light_side)
    throw ParameterError(fmt::format(
        "material error: material '{}' samples {} x {} texels, {} views, {} lights; the BTF "
        "'{}' {} x {}, {}, {}",
        material.backend(), s.resolution, s.resolution, s.view_count(), s.light_count(),
        full.material(), f.resolution, f.resolution, f.view_count(), f.light_count()));
  const HemisphereGrid lights(full.light_side());
  std::vector<double> cosine = lights.projected_solid_angles();
  for (double& c : cosine) c /= lights.cell_solid_angle();
  const int nv = full.view_count(), nl = full.light_count();
  std::vector<Partial> per_texel(static_cast<std::size_t>(full.texel_count()));
  tbb::parallel_for(0, full.texel_count(), [&](int t) {
    Partial p;
    std::array<double, 3> peak{};
    for (int v = 0; v < nv; ++v)
      for (int j = 0; j < nl; ++j) {
        const Rgb b = full.value(t, v, j);
        for (int c = 0; c < 3; ++c)
          peak[c] = std::max(peak[c], std::abs(static_cast<double>(b[c])));
      }
    for (int v = 0; v < nv; ++v) {
      std::array<double, 3> white_d{}, white_b{};
      for (int j = 0; j < nl; ++j) {
        const Rgb a = material.reflectance(t, v, j), b = full.value(t, v, j);
        for (int c = 0; c < 3; ++c) {
          const double ref = b[c], d = static_cast<double>(a[c]) - ref, ad = std::abs(d);
          p.diff2 += d * d;
          p.ref2 += ref * ref;
          p.max_abs = std::max(p.max_abs, ad);
          p.abs_sum += ad;
          if (ref != 0.0) {
            p.rel_sum += ad / std::abs(ref);
            ++p.rel_count;
          } else {
            ++p.zero;
          }
          if (peak[c] > 0.0) {
            p.floored_sum += ad / std::max(std::abs(ref), kRelativeErrorFloor * peak[c]);
            ++p.floored_count;
          }
          p.cos_diff2 += cosine[static_cast<std::size_t>(j)] * d * d;
          p.cos_ref2 += cosine[static_cast<std::size_t>(j)] * ref * ref;
          white_d[c] += d;
          white_b[c] += ref;
        }
      }
      for (int c = 0; c < 3; ++c) {
        p.white_diff2 += white_d[c] * white_d[c];
        p.white_ref2 += white_b[c] * white_b[c];
      }
    }
    per_texel[static_cast<std::size_t>(t)] = p;
  });
  Partial sum;
  double worst = std::numeric_limits<double>::quiet_NaN();
  for (const auto& p : per_texel) {
    sum.diff2 += p.diff2;
    sum.ref2 += p.ref2;
    sum.max_abs = std::max(sum.max_abs, p.max_abs);
    sum.rel_sum += p.rel_sum;
    sum.rel_count += p.rel_count;
    sum.floored_sum += p.floored_sum;
    sum.floored_count += p.floored_count;
    sum.abs_sum += p.abs_sum;
    sum.zero += p.zero;
    sum.cos_diff2 += p.cos_diff2;
    sum.cos_ref2 += p.cos_ref2;
    sum.white_diff2 += p.white_diff2;
    sum.white_ref2 += p.white_ref2;
    if (p.rel_count > 0) {
      const double mean = p.rel_sum / static_cast<double>(p.rel_count);
      if (!(worst >= mean)) worst = mean;
    }
  }
  const std::string name = "material '" + material.backend() + "'";
  MaterialError e;
  e.reference_l2 = std::sqrt(sum.ref2);
  e.relative_l2 = relative_to(std::sqrt(sum.diff2), e.reference_l2, "relative L2 error of " + name);
  e.max_abs = sum.max_abs;
  e.samples = static_cast<std::uint64_t>(full.value_count());
  e.average_relative = mean_or_nan(sum.rel_sum, sum.rel_count);
  e.average_relative_worst_abrdf = worst;
  e.average_relative_floored = mean_or_nan(sum.floored_sum, sum.floored_count);
  e.average_abs = mean_or_nan(sum.abs_sum, e.samples);
  e.zero_samples = sum.zero;
  e.cosine_l2 = relative_to(std::sqrt(sum.cos_diff2), std::sqrt(sum.cos_ref2),
                            "cosine-weighted relative L2 error of " + name);
  e.white_light_l2 = relative_to(std::sqrt(sum.white_diff2), std::sqrt(sum.white_ref2),
                                 "white-light relative L2 error of " + name);
  return e;
}

}  // namespace prt
