// Test-only backend `sh_probe`: one work-item per vertex. The vertex's M rows of T (CSR) give
// L*_j, and c_i = sum_j P[i, j] L*_j (P order^2 x M, row-major) accumulate in private memory.
// Host defines: PRT_COLUMN_T, PRT_SH_COUNT (order^2), PRT_LOCAL_COUNT (M).
#ifndef PRT_COLUMN_T
#define PRT_COLUMN_T ushort
#endif

__kernel PRT_WG_ATTR void sh_probe_relight(const uint vertices, const float scale,
                                           __global const uint* restrict offsets,
                                           __global const PRT_COLUMN_T* restrict columns,
                                           __global const uchar* restrict counts,
                                           __global const float* restrict projection,
                                           __global const float4* restrict light,
                                           __global float* restrict out) {
  const uint v = get_global_id(0);
  PRT_GUARD(v, vertices);
  float4 c[PRT_SH_COUNT];
  for (int i = 0; i < PRT_SH_COUNT; ++i) c[i] = (float4)(0.0f);
  for (int j = 0; j < PRT_LOCAL_COUNT; ++j) {
    const uint row = v * PRT_LOCAL_COUNT + j;
    float4 s = (float4)(0.0f);
    for (uint e = offsets[row]; e < offsets[row + 1]; ++e)
      s += convert_float(counts[e]) * light[columns[e]];
    s *= scale;
    for (int i = 0; i < PRT_SH_COUNT; ++i) c[i] += projection[i * PRT_LOCAL_COUNT + j] * s;
  }
  for (int i = 0; i < PRT_SH_COUNT; ++i) prt_store_rgb3(out, v * PRT_SH_COUNT + i, c[i]);
}
