// Backend `cpca_sh`: per-vertex SH coefficients of the transferred radiance from a clustered-PCA
// encoding of the SH transfer matrices (compressors/cpca_sh/README.md), in two kernels, the
// paper's per-cluster products and per-vertex blend:
//
//   cpca_sh_products        one work-item per (representative r, row i): q[r rows + i] =
//                           sum_k X_r[i, k] l_k, over k in increasing order.
//   cpca_sh_blend           one work-item per (vertex p, row i): q[f rows + i] + sum_j w_j
//                           q[(f + 1 + j) rows + i] over the vertex's cluster (s8 weights: the
//                           sum times the vertex's scale).
//   cpca_sh_blend_vertices  the rows of a vertex subset only (the frame loop's culling).
//
// The C++ reference (cpca_sh_relight.cpp) sums in the same order. Host defines: PRT_ID_T
// (uchar, ushort or uint), PRT_WEIGHT_FORMAT (0 float, 1 IEEE half, 2 s8 codes). The light and
// the products are float4 (RGB + pad); the output is packed RGB.

#ifndef PRT_ID_T
#define PRT_ID_T uchar
#endif
#ifndef PRT_WEIGHT_FORMAT
#define PRT_WEIGHT_FORMAT 0
#endif

#if PRT_WEIGHT_FORMAT == 0
#define CPCA_SH_WEIGHT_T float
#define CPCA_SH_WEIGHT(i) weights[i]
#elif PRT_WEIGHT_FORMAT == 1
#define CPCA_SH_WEIGHT_T half
#define CPCA_SH_WEIGHT(i) vload_half((i), weights)
#else
#define CPCA_SH_WEIGHT_T char
#define CPCA_SH_WEIGHT(i) convert_float(weights[i])
#endif

__kernel PRT_WG_ATTR void cpca_sh_products(const uint items, const uint n,
                                           __global const float* restrict representatives,
                                           __global const float4* restrict light,
                                           __global float4* restrict products) {
  const uint g = get_global_id(0);
  PRT_GUARD(g, items);
  __global const float* m = representatives + (size_t)g * n;
  float4 acc = (float4)(0.0f);
  for (uint k = 0; k < n; ++k) acc += m[k] * light[k];
  products[g] = acc;
}

inline float4 cpca_sh_row(const uint vertex, const uint i, const uint rows,
                          __global const PRT_ID_T* restrict ids,
                          __global const uint* restrict first,
                          __global const uint* restrict weight_offsets,
                          __global const CPCA_SH_WEIGHT_T* restrict weights,
                          __global const float* restrict vertex_scales,
                          __global const float4* restrict products) {
  const uint c = ids[vertex];
  const uint f = first[c];
  const uint k = first[c + 1] - f - 1;
  const uint off = weight_offsets[vertex];
  float4 acc = (float4)(0.0f);
  for (uint j = 0; j < k; ++j) acc += CPCA_SH_WEIGHT(off + j) * products[(f + 1 + j) * rows + i];
#if PRT_WEIGHT_FORMAT == 2
  return products[f * rows + i] + vertex_scales[vertex] * acc;
#else
  return products[f * rows + i] + acc;
#endif
}

__kernel PRT_WG_ATTR void cpca_sh_blend(const uint items, const uint rows,
                                        __global const PRT_ID_T* restrict ids,
                                        __global const uint* restrict first,
                                        __global const uint* restrict weight_offsets,
                                        __global const CPCA_SH_WEIGHT_T* restrict weights,
                                        __global const float* restrict vertex_scales,
                                        __global const float4* restrict products,
                                        __global float* restrict out) {
  const uint g = get_global_id(0);
  PRT_GUARD(g, items);
  prt_store_rgb3(out, g,
                 cpca_sh_row(g / rows, g % rows, rows, ids, first, weight_offsets, weights,
                             vertex_scales, products));
}

// Work-item g writes row g % rows of vertex vertex_ids[g / rows]; other rows of `out` are not
// written.
__kernel PRT_WG_ATTR void cpca_sh_blend_vertices(
    const uint items, const uint rows, __global const uint* restrict vertex_ids,
    __global const PRT_ID_T* restrict ids, __global const uint* restrict first,
    __global const uint* restrict weight_offsets,
    __global const CPCA_SH_WEIGHT_T* restrict weights,
    __global const float* restrict vertex_scales, __global const float4* restrict products,
    __global float* restrict out) {
  const uint g = get_global_id(0);
  PRT_GUARD(g, items);
  const uint vertex = vertex_ids[g / rows];
  const uint i = g % rows;
  prt_store_rgb3(out, vertex * rows + i,
                 cpca_sh_row(vertex, i, rows, ids, first, weight_offsets, weights, vertex_scales,
                             products));
}
