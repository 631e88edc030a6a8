// The C++ relight of backend `srbf_cta`, the reference of srbf_cta.cl: the same four steps with
// the same index order of every sum, in float RGB + pad lanes as the kernels' float4, so the two
// differ only by FMA contraction.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "srbf_cta/srbf_cta.h"

namespace prt::srbf_cta {
namespace {

typedef float Float4 __attribute__((vector_size(16)));

}  // namespace

std::vector<Rgb> cluster_matrices(const SrbfCtaArrays& a, std::span<const Rgb> light) {
  const std::size_t c_n = a.clusters(), nt = static_cast<std::size_t>(a.srbf_count),
                    r1 = static_cast<std::size_t>(a.rank_view),
                    r2 = static_cast<std::size_t>(a.rank_light),
                    r3 = static_cast<std::size_t>(a.rank_vertex),
                    m_n = static_cast<std::size_t>(a.local_count);
  std::vector<Float4> l(nt);
  for (std::size_t k = 0; k < nt; ++k) l[k] = Float4{light[k].x, light[k].y, light[k].z, 0.f};
  std::vector<Rgb> q(c_n * m_n * r3);
  tbb::parallel_for(std::size_t{0}, c_n, [&](std::size_t c) {
    // L'_c = U_c^T L'
    std::vector<Float4> lc(r2), rm(r1 * r3);
    for (std::size_t i = 0; i < r2; ++i) {
      Float4 acc{};
      for (std::size_t k = 0; k < nt; ++k) acc += a.light_bases[(c * nt + k) * r2 + i] * l[k];
      lc[i] = acc;
    }
    // R_c(a, j) = refold(V_cj)(a, :) . L'_c
    for (std::size_t ia = 0; ia < r1; ++ia)
      for (std::size_t j = 0; j < r3; ++j) {
        Float4 acc{};
        const float* v = a.duals.data() + ((c * r3 + j) * r1 + ia) * r2;
        for (std::size_t b = 0; b < r2; ++b) acc += v[b] * lc[b];
        rm[ia * r3 + j] = acc;
      }
    // Q_c = U R_c
    for (std::size_t m = 0; m < m_n; ++m)
      for (std::size_t j = 0; j < r3; ++j) {
        Float4 acc{};
        for (std::size_t ia = 0; ia < r1; ++ia) acc += a.view_basis[m * r1 + ia] * rm[ia * r3 + j];
        q[(c * m_n + m) * r3 + j] = Rgb(acc[0], acc[1], acc[2]);
      }
  });
  return q;
}

void blend_vertices(const SrbfCtaArrays& a, std::span<const Rgb> q,
                    std::span<const std::uint32_t> vertices, bool all, std::span<Rgb> out) {
  const std::size_t r3 = static_cast<std::size_t>(a.rank_vertex),
                    m_n = static_cast<std::size_t>(a.local_count);
  const std::size_t count = all ? a.vertices : vertices.size();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 64), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const std::size_t x = all ? i : vertices[i];
      const std::size_t c = a.ids[x];
      const float* w = a.weights.data() + x * r3;
      for (std::size_t m = 0; m < m_n; ++m) {
        Float4 acc{};
        const Rgb* qm = q.data() + (c * m_n + m) * r3;
        for (std::size_t j = 0; j < r3; ++j) acc += w[j] * Float4{qm[j].x, qm[j].y, qm[j].z, 0.f};
        out[x * m_n + m] = Rgb(acc[0], acc[1], acc[2]);
      }
    }
  });
}

}  // namespace prt::srbf_cta
