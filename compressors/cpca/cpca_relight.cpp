// The C++ relight of backend `cpca`: the reference of cpca.cl, summing in the kernel's order
// (a representative's dot in 64 strided lanes reduced pairwise; a row's weighted sum in vector
// order, added to the mean's product last), so the two differ only by FMA contraction.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "cpca/cpca.h"

namespace prt::cpca {
namespace {

typedef float Float4 __attribute__((vector_size(16)));

constexpr std::size_t kLanes = 64;

Float4 to_float4(const Rgb& v) {
  return Float4{v.x, v.y, v.z, 0.f};
}

struct Blend {
  const CpcaArrays& a;
  const std::vector<Float4>& q;

  Rgb operator()(std::size_t row) const {
    const std::uint32_t c = a.ids[row];
    const std::uint32_t f = a.first[c];
    const std::uint32_t k = a.first[c + 1] - f - 1;
    const float* w = a.weight_values.data() + a.weight_offsets[row];
    Float4 acc{};
    for (std::uint32_t i = 0; i < k; ++i) acc += w[i] * q[f + 1 + i];
    const Float4 s = a.format == WeightFormat::kS8 ? q[f] + a.row_scales[row] * acc : q[f] + acc;
    return Rgb(s[0], s[1], s[2]);
  }
};

std::vector<Float4> as_float4(std::span<const Rgb> q) {
  std::vector<Float4> out(q.size());
  for (std::size_t i = 0; i < q.size(); ++i) out[i] = to_float4(q[i]);
  return out;
}

}  // namespace

std::vector<Rgb> representative_dots(const CpcaArrays& a, std::span<const Rgb> light) {
  const auto n = static_cast<std::size_t>(a.pixel_count);
  std::vector<Float4> l(n);
  for (std::size_t j = 0; j < n; ++j) l[j] = to_float4(light[j]);
  std::vector<Rgb> out(a.rep_count());
  tbb::parallel_for(std::size_t{0}, a.rep_count(), [&](std::size_t r) {
    const float* rep = a.reps.data() + r * n;
    // Lane-inner: the 64 lanes' chains side by side, each lane still summed in j order.
    Float4 lanes[kLanes] = {};
    std::size_t j0 = 0;
    for (; j0 + kLanes <= n; j0 += kLanes)
      for (std::size_t lane = 0; lane < kLanes; ++lane)
        lanes[lane] += rep[j0 + lane] * l[j0 + lane];
    for (std::size_t lane = 0; j0 + lane < n; ++lane) lanes[lane] += rep[j0 + lane] * l[j0 + lane];
    for (std::size_t s = kLanes / 2; s > 0; s /= 2) {
      for (std::size_t lane = 0; lane < s; ++lane) lanes[lane] += lanes[lane + s];
    }
    out[r] = Rgb(lanes[0][0], lanes[0][1], lanes[0][2]);
  });
  return out;
}

void blend_rows(const CpcaArrays& a, std::span<const Rgb> q, std::span<Rgb> out) {
  const std::vector<Float4> q4 = as_float4(q);
  const Blend blend{a, q4};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, a.rows(), 4096), [&](const auto& r) {
    for (std::size_t row = r.begin(); row != r.end(); ++row) out[row] = blend(row);
  });
}

void apply_view(const CpcaArrays& a, std::span<const Rgb> terms, std::span<Rgb> out) {
  const auto m = static_cast<std::size_t>(a.local_count);
  const auto k = static_cast<std::size_t>(a.view_terms);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, a.vertices, 64), [&](const auto& r) {
    for (std::size_t x = r.begin(); x != r.end(); ++x) {
      const Rgb* y = terms.data() + x * k;
      for (std::size_t o = 0; o < m; ++o) {
        const float* phi = a.view.data() + o * k;
        Float4 acc{};
        for (std::size_t i = 0; i < k; ++i) acc += phi[i] * to_float4(y[i]);
        out[x * m + o] = Rgb(acc[0], acc[1], acc[2]);
      }
    }
  });
}

void blend_vertex_rows(const CpcaArrays& a, std::span<const Rgb> q,
                       std::span<const std::uint32_t> vertices, std::span<Rgb> out) {
  const std::vector<Float4> q4 = as_float4(q);
  const Blend blend{a, q4};
  const auto m = static_cast<std::size_t>(a.local_count);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertices.size(), 64), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const std::size_t base = static_cast<std::size_t>(vertices[i]) * m;
      for (std::size_t j = 0; j < m; ++j) out[base + j] = blend(base + j);
    }
  });
}

}  // namespace prt::cpca
