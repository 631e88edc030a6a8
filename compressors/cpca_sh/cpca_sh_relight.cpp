// The C++ relight of backend `cpca_sh`: the reference of cpca_sh.cl, summing in the kernel's
// order (a representative's product over the light coefficients in increasing k; a vertex's
// weighted sum in vector order, added to the mean's product last), so the two differ only by
// FMA contraction.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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

// Writes the rows coefficients of vertex p.
struct Blend {
  const CpcaShArrays& a;
  const std::vector<Float4>& q;

  void operator()(std::size_t p, std::span<Rgb> out) const {
    const auto rows = static_cast<std::size_t>(a.rows());
    const std::uint32_t c = a.ids[p];
    const std::uint32_t f = a.first[c];
    const std::uint32_t k = a.first[c + 1] - f - 1;
    const float* w = a.weight_values.data() + a.weight_offsets[p];
    for (std::size_t i = 0; i < rows; ++i) {
      Float4 acc{};
      for (std::uint32_t j = 0; j < k; ++j) acc += w[j] * q[(f + 1 + j) * rows + i];
      const Float4 mean = q[f * rows + i];
      const Float4 s = a.format == WeightFormat::kS8 ? mean + a.vertex_scales[p] * acc : mean + acc;
      out[p * rows + i] = Rgb(s[0], s[1], s[2]);
    }
  }
};

}  // namespace

std::vector<Rgb> representative_products(const CpcaShArrays& a, std::span<const Rgb> light) {
  const auto n = static_cast<std::size_t>(a.n());
  const auto rows = static_cast<std::size_t>(a.rows());
  std::vector<Float4> l(n);
  for (std::size_t k = 0; k < n; ++k) l[k] = to_float4(light[k]);
  std::vector<Rgb> out(a.rep_count() * rows);
  tbb::parallel_for(std::size_t{0}, out.size(), [&](std::size_t g) {
    const float* m = a.reps.data() + g * n;  // rep g / rows, row g % rows
    Float4 acc{};
    for (std::size_t k = 0; k < n; ++k) acc += m[k] * l[k];
    out[g] = Rgb(acc[0], acc[1], acc[2]);
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
