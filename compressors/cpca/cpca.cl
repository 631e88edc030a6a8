// Backend `cpca`: L* = T~ L with T~ clustered-PCA encoded (compressors/cpca/README.md), in two
// kernels, the paper's per-cluster products and per-point blend:
//
//   cpca_dots           one work-group of 64 per representative (cluster mean or vector): its
//                       dot product with the light, in 64 strided lanes reduced pairwise.
//   cpca_blend          one work-item per row: q[first] + sum_i w_i q[first + 1 + i] over the
//                       row's cluster (s8 weights: the sum times the row's scale).
//   cpca_blend_vertices the rows of a vertex subset only (the frame loop's culling).
//   cpca_view           signal=brdf: one work-item per output value (vertex x, view cell o):
//                       sum_k Phi[o, k] y[x K + k] over the K blended rows of the vertex.
//
// The C++ reference (cpca_relight.cpp) sums in the same order. Host defines: PRT_ID_T (uchar,
// ushort or uint), PRT_WEIGHT_FORMAT (0 float, 1 IEEE half, 2 s8 codes), PRT_WG_SIZE (64).
// The light and the products are float4 (RGB + pad); the output is packed RGB.

#ifndef PRT_ID_T
#define PRT_ID_T uchar
#endif
#ifndef PRT_WEIGHT_FORMAT
#define PRT_WEIGHT_FORMAT 0
#endif

#if PRT_WEIGHT_FORMAT == 0
#define CPCA_WEIGHT_T float
#define CPCA_WEIGHT(i) weights[i]
#elif PRT_WEIGHT_FORMAT == 1
#define CPCA_WEIGHT_T half
#define CPCA_WEIGHT(i) vload_half((i), weights)
#else
#define CPCA_WEIGHT_T char
#define CPCA_WEIGHT(i) convert_float(weights[i])
#endif

__kernel PRT_WG_ATTR void cpca_dots(const uint reps, const uint n,
                                    __global const float* restrict representatives,
                                    __global const float4* restrict light,
                                    __global float4* restrict products) {
  __local float4 lanes[PRT_WG_SIZE];
  const uint rep = get_group_id(0);
  const uint lane = get_local_id(0);
  float4 acc = (float4)(0.0f);
  if (rep < reps) {
    __global const float* v = representatives + (size_t)rep * n;
    for (uint j = lane; j < n; j += PRT_WG_SIZE) acc += v[j] * light[j];
  }
  lanes[lane] = acc;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint s = PRT_WG_SIZE / 2; s > 0; s >>= 1) {
    if (lane < s) lanes[lane] += lanes[lane + s];
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  if (lane == 0 && rep < reps) products[rep] = lanes[0];
}

inline float4 cpca_row(const uint row, __global const PRT_ID_T* restrict ids,
                       __global const uint* restrict first,
                       __global const uint* restrict weight_offsets,
                       __global const CPCA_WEIGHT_T* restrict weights,
                       __global const float* restrict row_scales,
                       __global const float4* restrict products) {
  const uint c = ids[row];
  const uint f = first[c];
  const uint k = first[c + 1] - f - 1;
  const uint off = weight_offsets[row];
  float4 acc = (float4)(0.0f);
  for (uint i = 0; i < k; ++i) acc += CPCA_WEIGHT(off + i) * products[f + 1 + i];
#if PRT_WEIGHT_FORMAT == 2
  return products[f] + row_scales[row] * acc;
#else
  return products[f] + acc;
#endif
}

__kernel PRT_WG_ATTR void cpca_blend(const uint rows, __global const PRT_ID_T* restrict ids,
                                     __global const uint* restrict first,
                                     __global const uint* restrict weight_offsets,
                                     __global const CPCA_WEIGHT_T* restrict weights,
                                     __global const float* restrict row_scales,
                                     __global const float4* restrict products,
                                     __global float* restrict out) {
  const uint row = get_global_id(0);
  PRT_GUARD(row, rows);
  prt_store_rgb3(out, row,
                 cpca_row(row, ids, first, weight_offsets, weights, row_scales, products));
}

// Work-item i blends row vertex_ids[i / dim] * dim + i % dim; other rows of `out` are not
// written.
__kernel PRT_WG_ATTR void cpca_blend_vertices(
    const uint subset_rows, const uint dim, __global const uint* restrict vertex_ids,
    __global const PRT_ID_T* restrict ids, __global const uint* restrict first,
    __global const uint* restrict weight_offsets, __global const CPCA_WEIGHT_T* restrict weights,
    __global const float* restrict row_scales, __global const float4* restrict products,
    __global float* restrict out) {
  const uint item = get_global_id(0);
  PRT_GUARD(item, subset_rows);
  const uint row = vertex_ids[item / dim] * dim + item % dim;
  prt_store_rgb3(out, row,
                 cpca_row(row, ids, first, weight_offsets, weights, row_scales, products));
}

// out[x M + o] = sum_k view[o K + k] terms[x K + k], k ascending.
__kernel PRT_WG_ATTR void cpca_view(const uint outputs, const uint m, const uint k,
                                    __global const float* restrict view,
                                    __global const float* restrict terms,
                                    __global float* restrict out) {
  const uint item = get_global_id(0);
  PRT_GUARD(item, outputs);
  const uint x = item / m, o = item % m;
  __global const float* phi = view + (size_t)o * k;
  float4 acc = (float4)(0.0f);
  for (uint i = 0; i < k; ++i) acc += phi[i] * prt_load_rgb3(terms, (size_t)x * k + i);
  prt_store_rgb3(out, item, acc);
}
