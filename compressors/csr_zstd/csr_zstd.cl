// Backend `csr_zstd`: L* = T L over T's CSR arrays, which the host decompresses from the zstd
// frames and uploads before every launch (csr_zstd_opencl.cpp); with a vertex subset only the
// frames holding its rows. One work-item per row, four
// independent float4 accumulators over the u8 counts, then the common scale 1/s^2: the order of
// the C++ reference (csr_zstd_relight.cpp).
//
// Host defines: PRT_COLUMN_T (ushort or uint), PRT_WG_SIZE. The light is float4 (RGB + pad);
// the output is packed RGB (3 floats per row), the layout of prt::LocalRadiance.

#ifndef PRT_COLUMN_T
#define PRT_COLUMN_T ushort
#endif

// One row's sum: both kernels call it, so a subset row has the full kernel's bits.
float4 csr_zstd_row(const uint row, const float scale, __global const uint* restrict offsets,
                    __global const PRT_COLUMN_T* restrict columns,
                    __global const uchar* restrict counts, __global const float4* restrict light) {
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
  return ((a0 + a1) + (a2 + a3)) * scale;
}

__kernel PRT_WG_ATTR void csr_zstd_rows(const uint rows, const float scale,
                                        __global const uint* restrict offsets,
                                        __global const PRT_COLUMN_T* restrict columns,
                                        __global const uchar* restrict counts,
                                        __global const float4* restrict light,
                                        __global float* restrict out) {
  const uint row = get_global_id(0);
  PRT_GUARD(row, rows);
  prt_store_rgb3(out, row, csr_zstd_row(row, scale, offsets, columns, counts, light));
}

// The rows of the vertices in vertex_ids only (work-item i: row vertex_ids[i / dim] * dim +
// i % dim). The host uploads only the frames holding those rows, so other rows' offsets and
// entries may be stale: they are not read, and other rows of `out` are not written.
__kernel PRT_WG_ATTR void csr_zstd_vertices(const uint subset_rows, const uint dim,
                                            __global const uint* restrict vertex_ids,
                                            const float scale,
                                            __global const uint* restrict offsets,
                                            __global const PRT_COLUMN_T* restrict columns,
                                            __global const uchar* restrict counts,
                                            __global const float4* restrict light,
                                            __global float* restrict out) {
  const uint item = get_global_id(0);
  PRT_GUARD(item, subset_rows);
  const uint row = vertex_ids[item / dim] * dim + item % dim;
  prt_store_rgb3(out, row, csr_zstd_row(row, scale, offsets, columns, counts, light));
}
