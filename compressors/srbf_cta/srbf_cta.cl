// Backend `srbf_cta` (compressors/srbf_cta/README.md): the relight of Tsai and Shih 2006,
// section 6, in four launches, each sum over increasing index as the C++ reference
// (srbf_cta_relight.cpp). RGB travels as float4 (RGB + pad); the output is packed RGB.
//
//   srbf_cta_light     per (cluster c, i < R2):        Lc = U_c^T L'
//   srbf_cta_cores     per (cluster, a < R1, j < R3):  R_c(a, j) = refold(V_cj)(a, :) . Lc
//   srbf_cta_expand    per (cluster, m < M, j < R3):   Q_c(m, j) = U(m, :) . R_c(:, j)
//   srbf_cta_vertices  per (vertex x, m < M):          L*_x(m) = Q_c(m, :) . W_x
//   srbf_cta_vertices_subset  the same for a vertex list (the frame loop's culling)

__kernel PRT_WG_ATTR void srbf_cta_light(const uint items, const uint nt, const uint r2,
                                         __global const float* restrict light_bases,
                                         __global const float4* restrict light,
                                         __global float4* restrict lc) {
  const uint g = get_global_id(0);
  PRT_GUARD(g, items);
  const uint c = g / r2, i = g % r2;
  __global const float* u = light_bases + (size_t)c * nt * r2 + i;
  float4 acc = (float4)(0.0f);
  for (uint k = 0; k < nt; ++k) acc += u[(size_t)k * r2] * light[k];
  lc[g] = acc;
}

__kernel PRT_WG_ATTR void srbf_cta_cores(const uint items, const uint r1, const uint r2,
                                         const uint r3, __global const float* restrict duals,
                                         __global const float4* restrict lc,
                                         __global float4* restrict cores) {
  const uint g = get_global_id(0);
  PRT_GUARD(g, items);
  const uint c = g / (r1 * r3), rest = g % (r1 * r3), a = rest / r3, j = rest % r3;
  __global const float* v = duals + (((size_t)c * r3 + j) * r1 + a) * r2;
  __global const float4* l = lc + (size_t)c * r2;
  float4 acc = (float4)(0.0f);
  for (uint b = 0; b < r2; ++b) acc += v[b] * l[b];
  cores[g] = acc;
}

__kernel PRT_WG_ATTR void srbf_cta_expand(const uint items, const uint m_n, const uint r1,
                                          const uint r3, __global const float* restrict view,
                                          __global const float4* restrict cores,
                                          __global float4* restrict q) {
  const uint g = get_global_id(0);
  PRT_GUARD(g, items);
  const uint c = g / (m_n * r3), rest = g % (m_n * r3), m = rest / r3, j = rest % r3;
  __global const float4* rc = cores + (size_t)c * r1 * r3 + j;
  float4 acc = (float4)(0.0f);
  for (uint a = 0; a < r1; ++a) acc += view[m * r1 + a] * rc[(size_t)a * r3];
  q[g] = acc;
}

inline void srbf_cta_vertex_row(const uint x, const uint m, const uint m_n, const uint r3,
                                __global const uint* restrict ids,
                                __global const float* restrict weights,
                                __global const float4* restrict q, __global float* restrict out) {
  __global const float4* qm = q + ((size_t)ids[x] * m_n + m) * r3;
  __global const float* w = weights + (size_t)x * r3;
  float4 acc = (float4)(0.0f);
  for (uint j = 0; j < r3; ++j) acc += w[j] * qm[j];
  prt_store_rgb3(out, (size_t)x * m_n + m, acc);
}

__kernel PRT_WG_ATTR void srbf_cta_vertices(const uint items, const uint m_n, const uint r3,
                                            __global const uint* restrict ids,
                                            __global const float* restrict weights,
                                            __global const float4* restrict q,
                                            __global float* restrict out) {
  const uint g = get_global_id(0);
  PRT_GUARD(g, items);
  srbf_cta_vertex_row(g / m_n, g % m_n, m_n, r3, ids, weights, q, out);
}

__kernel PRT_WG_ATTR void srbf_cta_vertices_subset(const uint items, const uint m_n, const uint r3,
                                                   __global const uint* restrict vertices,
                                                   __global const uint* restrict ids,
                                                   __global const float* restrict weights,
                                                   __global const float4* restrict q,
                                                   __global float* restrict out) {
  const uint g = get_global_id(0);
  PRT_GUARD(g, items);
  srbf_cta_vertex_row(vertices[g / m_n], g % m_n, m_n, r3, ids, weights, q, out);
}
