// The C++ relight of backend `cpca_sh`: the reference of cpca_sh.cl, summing in the kernel's
// order (a representative's product over the light coefficients in increasing k; a vertex's
// weighted sum in vector order, added to the mean's product last), so the two differ only by
// FMA contraction.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

#include "cpca_sh/cpca_sh.h"

namespace prt::cpca_sh {
namespace {

typedef float Float4 __attribute__((vector_size(16)));

Float4 to_float4(const Rgb& v) {
  return Float4{v.x, v.y, v.z, 0.f};
}

std::vector<Float4> as_float4(std::span<const Rgb> q) {
  std::vector<Float4> out(q.size());
  for (std::size_t i = 0; i < q.size(); ++i) out[i] = to_float4(q[i]);
  return out;
}

// Writes the rows coefficients of vertex p. The rows go in tiles of kTile accumulators side by
// side, each summed over j in vector order as the kernel sums it: one accumulator would be one
// chain of dependent multiply-adds (with FMA contraction, a chain of the FMA's longer latency).
struct Blend {
  static constexpr std::size_t kTile = 8;
  const CpcaShArrays& a;
  const std::vector<Float4>& q;

  void operator()(std::size_t p, std::span<Rgb> out) const {
    const auto rows = static_cast<std::size_t>(a.rows());
    const std::uint32_t c = a.ids[p];
    const std::uint32_t f = a.first[c];
    const std::uint32_t k = a.first[c + 1] - f - 1;
    const float* w = a.weight_values.data() + a.weight_offsets[p];
    const bool scaled = a.format == WeightFormat::kS8;
    for (std::size_t i0 = 0; i0 < rows; i0 += kTile) {
      const std::size_t n = std::min(kTile, rows - i0);
      Float4 acc[kTile] = {};
      for (std::uint32_t j = 0; j < k; ++j) {
        const Float4* qj = q.data() + (f + 1 + j) * rows + i0;
        const float wj = w[j];
        for (std::size_t t = 0; t < n; ++t) acc[t] += wj * qj[t];
      }
      const Float4* mean = q.data() + f * rows + i0;
      for (std::size_t t = 0; t < n; ++t) {
        const Float4 s = scaled ? mean[t] + a.vertex_scales[p] * acc[t] : mean[t] + acc[t];
        out[p * rows + i0 + t] = Rgb(s[0], s[1], s[2]);
      }
    }
  }
};

}  // namespace

std::vector<Rgb> representative_products(const CpcaShArrays& a, std::span<const Rgb> light) {
  const auto n = static_cast<std::size_t>(a.n());
  const auto rows = static_cast<std::size_t>(a.rows());
  std::vector<Float4> l(n);
  for (std::size_t k = 0; k < n; ++k) l[k] = to_float4(light[k]);
  // kTile products side by side, each summed over k in increasing order as the kernel sums
  // it, so the multiply-adds of one are not a single dependent chain.
  constexpr std::size_t kTile = 4;
  std::vector<Rgb> out(a.rep_count() * rows);
  const std::size_t tiles = (out.size() + kTile - 1) / kTile;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tiles, 16), [&](const auto& range) {
    for (std::size_t tile = range.begin(); tile != range.end(); ++tile) {
      const std::size_t g0 = tile * kTile;
      const std::size_t count = std::min(kTile, out.size() - g0);
      const float* m = a.reps.data() + g0 * n;  // rep g / rows, row g % rows
      Float4 acc[kTile] = {};
      if (count == kTile) {
        for (std::size_t k = 0; k < n; ++k)
          for (std::size_t t = 0; t < kTile; ++t) acc[t] += m[t * n + k] * l[k];
      } else {
        for (std::size_t k = 0; k < n; ++k)
          for (std::size_t t = 0; t < count; ++t) acc[t] += m[t * n + k] * l[k];
      }
      for (std::size_t t = 0; t < count; ++t) out[g0 + t] = Rgb(acc[t][0], acc[t][1], acc[t][2]);
    }
  });
  return out;
}

void blend_vertices(const CpcaShArrays& a, std::span<const Rgb> q, std::span<Rgb> out) {
  const std::vector<Float4> q4 = as_float4(q);
  const Blend blend{a, q4};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, a.vertices, 256), [&](const auto& r) {
    for (std::size_t p = r.begin(); p != r.end(); ++p) blend(p, out);
  });
}

void blend_vertex_subset(const CpcaShArrays& a, std::span<const Rgb> q,
                         std::span<const std::uint32_t> vertices, std::span<Rgb> out) {
  const std::vector<Float4> q4 = as_float4(q);
  const Blend blend{a, q4};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertices.size(), 256), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) blend(vertices[i], out);
  });
}

}  // namespace prt::cpca_sh
