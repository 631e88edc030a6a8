// The C++ relight of backend `sh_biscale`, the reference of sh_biscale.cl: per vertex and row i
// the sum over the light coefficients k in increasing order, in float RGB + pad lanes as the
// kernel's float4, so the two differ only by FMA contraction.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "sh_biscale/sh_biscale.h"

namespace prt::sh_biscale {
namespace {

typedef float Float4 __attribute__((vector_size(16)));

void relight_vertex(const ShBiscaleArrays& a, std::span<const Float4> l, std::size_t p,
                    std::span<Rgb> out) {
  const auto n = static_cast<std::size_t>(a.n());
  const float* m = a.matrices.data() + p * n * n;
  for (std::size_t i = 0; i < n; ++i) {
    Float4 acc{};
    for (std::size_t k = 0; k < n; ++k) acc += m[i * n + k] * l[k];
    out[p * n + i] = Rgb(acc[0], acc[1], acc[2]);
  }
}

}  // namespace

void relight_rows(const ShBiscaleArrays& a, std::span<const Rgb> light,
                  std::span<const std::uint32_t> vertices, bool all, std::span<Rgb> out) {
  std::vector<Float4> l(light.size());
  for (std::size_t k = 0; k < light.size(); ++k)
    l[k] = Float4{light[k].x, light[k].y, light[k].z, 0.f};
  const std::size_t count = all ? a.vertices : vertices.size();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 64), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i)
      relight_vertex(a, l, all ? i : vertices[i], out);
  });
}

}  // namespace prt::sh_biscale
