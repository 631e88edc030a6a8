// Backend `sh_biscale` (compressors/sh_biscale/README.md): the local SH coefficients of the
// transferred radiance, e_p = M_p l per vertex, one work-item per (vertex p, row i), summing over
// the light coefficients k in increasing order as the C++ reference (sh_biscale_relight.cpp).
// The light is float4 (RGB + pad); the output packed RGB.
//
//   sh_biscale_rows           every row of every vertex
//   sh_biscale_rows_vertices  the rows of a vertex subset only (the frame loop's culling)

inline void sh_biscale_row(const uint vertex, const uint i, const uint n,
                           __global const float* restrict matrices,
                           __global const float4* restrict light, __global float* restrict out) {
  __global const float* m = matrices + ((size_t)vertex * n + i) * n;
  float4 acc = (float4)(0.0f);
  for (uint k = 0; k < n; ++k) acc += m[k] * light[k];
  prt_store_rgb3(out, vertex * n + i, acc);
}

__kernel PRT_WG_ATTR void sh_biscale_rows(const uint items, const uint n,
                                          __global const float* restrict matrices,
                                          __global const float4* restrict light,
                                          __global float* restrict out) {
  const uint g = get_global_id(0);
  PRT_GUARD(g, items);
  sh_biscale_row(g / n, g % n, n, matrices, light, out);
}

__kernel PRT_WG_ATTR void sh_biscale_rows_vertices(const uint items, const uint n,
                                                   __global const uint* restrict vertices,
                                                   __global const float* restrict matrices,
                                                   __global const float4* restrict light,
                                                   __global float* restrict out) {
  const uint g = get_global_id(0);
  PRT_GUARD(g, items);
  sh_biscale_row(vertices[g / n], g % n, n, matrices, light, out);
}
