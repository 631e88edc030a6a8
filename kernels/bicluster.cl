// Backend `bicluster`: L* = sum_i B_i L + residual, in two kernels (Algorithm 2 of Sun et al.,
// docs/backends/bicluster.md):
//
//   bicluster_phase1   one work-item per bicluster: P_i = sum_m t_m L[k_m] (float4 RGB)
//   bicluster_phase2   one work-item per row: sum of P_i over the row's bicluster ids I_j, plus
//                      the row's residual 1x1 terms, times the scale 1/s^2
//
// Host defines: PRT_COLUMN_T (ushort or uint), PRT_WG_SIZE. Constants and residual counts are
// signed 16-bit counts. The light and P are float4 (RGB + pad); the output is packed RGB.

#ifndef PRT_COLUMN_T
#define PRT_COLUMN_T ushort
#endif

__kernel PRT_WG_ATTR void bicluster_phase1(const uint biclusters,
                                           __global const uint* restrict col_offsets,
                                           __global const PRT_COLUMN_T* restrict columns,
                                           __global const short* restrict constants,
                                           __global const float4* restrict light,
                                           __global float4* restrict products) {
  const uint i = get_global_id(0);
  PRT_GUARD(i, biclusters);
  const uint end = col_offsets[i + 1];
  float4 a0 = (float4)(0.0f), a1 = (float4)(0.0f);
  uint q = col_offsets[i];
  for (; q + 2 <= end; q += 2) {
    a0 += convert_float(constants[q]) * light[columns[q]];
    a1 += convert_float(constants[q + 1]) * light[columns[q + 1]];
  }
  if (q < end) a0 += convert_float(constants[q]) * light[columns[q]];
  products[i] = a0 + a1;
}

__kernel PRT_WG_ATTR void bicluster_phase2(const uint rows, const float scale,
                                           __global const uint* restrict row_offsets,
                                           __global const uint* restrict row_bics,
                                           __global const float4* restrict products,
                                           __global const uint* restrict res_offsets,
                                           __global const PRT_COLUMN_T* restrict res_columns,
                                           __global const short* restrict res_counts,
                                           __global const float4* restrict light,
                                           __global float* restrict out) {
  const uint row = get_global_id(0);
  PRT_GUARD(row, rows);
  float4 a0 = (float4)(0.0f), a1 = (float4)(0.0f);
  uint q = row_offsets[row];
  const uint end = row_offsets[row + 1];
  for (; q + 2 <= end; q += 2) {
    a0 += products[row_bics[q]];
    a1 += products[row_bics[q + 1]];
  }
  if (q < end) a0 += products[row_bics[q]];
  const uint rend = res_offsets[row + 1];
  for (uint r = res_offsets[row]; r < rend; ++r)
    a1 += convert_float(res_counts[r]) * light[res_columns[r]];
  prt_store_rgb3(out, row, (a0 + a1) * scale);
}
