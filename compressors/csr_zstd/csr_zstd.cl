// Backend `csr_zstd`: L* = T L over T's CSR arrays, which the host decompresses from the zstd
// frames and uploads before every launch (csr_zstd_opencl.cpp). One work-item per row, four
// independent float4 accumulators over the u8 counts, then the common scale 1/s^2: the order of
// the C++ reference (csr_zstd_relight.cpp).
//
// Host defines: PRT_COLUMN_T (ushort or uint), PRT_WG_SIZE. The light is float4 (RGB + pad);
// the output is packed RGB (3 floats per row), the layout of prt::LocalRadiance.

#ifndef PRT_COLUMN_T
#define PRT_COLUMN_T ushort
#endif

__kernel PRT_WG_ATTR void csr_zstd_rows(const uint rows, const float scale,
                                        __global const uint* restrict offsets,
                                        __global const PRT_COLUMN_T* restrict columns,
                                        __global const uchar* restrict counts,
                                        __global const float4* restrict light,
                                        __global float* restrict out) {
  const uint row = get_global_id(0);
  PRT_GUARD(row, rows);
  uint i = offsets[row];
  const uint end = offsets[row + 1];
  float4 a0 = (float4)(0.0f), a1 = (float4)(0.0f), a2 = (float4)(0.0f), a3 = (float4)(0.0f);
  for (; i + 4 <= end; i += 4) {
    a0 += convert_float(counts[i + 0]) * light[columns[i + 0]];
    a1 += convert_float(counts[i + 1]) * light[columns[i + 1]];
    a2 += convert_float(counts[i + 2]) * light[columns[i + 2]];
    a3 += convert_float(counts[i + 3]) * light[columns[i + 3]];
  }
  for (; i < end; ++i) a0 += convert_float(counts[i]) * light[columns[i]];
  prt_store_rgb3(out, row, ((a0 + a1) + (a2 + a3)) * scale);
}
