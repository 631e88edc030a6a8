// Backend `csr_quantized`: L* = T~ L with T's CSR sparsity and quantised values, one kernel per
// value format, one work-item per row. Each sums its row with four independent float4
// accumulators combined as (a0 + a1) + (a2 + a3), the order of the C++ reference
// (csr_quantized_relight.cpp), so the two agree to FMA contraction.
//
//   csr_quantized_f32  values as float
//   csr_quantized_f16  values as IEEE half bits, read with vload_half (core OpenCL 1.2, no
//                      cl_khr_fp16 needed)
//   csr_quantized_u8   u8 codes; the row's sum is multiplied by its float scale
//
// Host defines: PRT_COLUMN_T (ushort or uint), PRT_WG_SIZE. The light is float4 (RGB + pad);
// the output is packed RGB (3 floats per row), the layout of prt::LocalRadiance.

#ifndef PRT_COLUMN_T
#define PRT_COLUMN_T ushort
#endif

// The row loop of all three kernels; VALUE(i) is the float multiplying the light at entry i.
#define CSR_QUANTIZED_ROW_SUM(VALUE)                                                   \
  uint i = offsets[row];                                                               \
  const uint end = offsets[row + 1];                                                   \
  float4 a0 = (float4)(0.0f), a1 = (float4)(0.0f), a2 = (float4)(0.0f),                \
         a3 = (float4)(0.0f);                                                          \
  for (; i + 4 <= end; i += 4) {                                                       \
    a0 += VALUE(i + 0) * light[columns[i + 0]];                                        \
    a1 += VALUE(i + 1) * light[columns[i + 1]];                                        \
    a2 += VALUE(i + 2) * light[columns[i + 2]];                                        \
    a3 += VALUE(i + 3) * light[columns[i + 3]];                                        \
  }                                                                                    \
  for (; i < end; ++i) a0 += VALUE(i) * light[columns[i]];                             \
  const float4 sum = (a0 + a1) + (a2 + a3)

#define CSR_QUANTIZED_F32(i) values[i]
#define CSR_QUANTIZED_F16(i) vload_half((i), values)
#define CSR_QUANTIZED_U8(i) convert_float(codes[i])

__kernel PRT_WG_ATTR void csr_quantized_f32(const uint rows, __global const uint* restrict offsets,
                                            __global const PRT_COLUMN_T* restrict columns,
                                            __global const float* restrict values,
                                            __global const float4* restrict light,
                                            __global float* restrict out) {
  const uint row = get_global_id(0);
  PRT_GUARD(row, rows);
  CSR_QUANTIZED_ROW_SUM(CSR_QUANTIZED_F32);
  prt_store_rgb3(out, row, sum);
}

__kernel PRT_WG_ATTR void csr_quantized_f16(const uint rows, __global const uint* restrict offsets,
                                            __global const PRT_COLUMN_T* restrict columns,
                                            __global const half* restrict values,
                                            __global const float4* restrict light,
                                            __global float* restrict out) {
  const uint row = get_global_id(0);
  PRT_GUARD(row, rows);
  CSR_QUANTIZED_ROW_SUM(CSR_QUANTIZED_F16);
  prt_store_rgb3(out, row, sum);
}

__kernel PRT_WG_ATTR void csr_quantized_u8(const uint rows, __global const uint* restrict offsets,
                                           __global const PRT_COLUMN_T* restrict columns,
                                           __global const uchar* restrict codes,
                                           __global const float* restrict row_scales,
                                           __global const float4* restrict light,
                                           __global float* restrict out) {
  const uint row = get_global_id(0);
  PRT_GUARD(row, rows);
  CSR_QUANTIZED_ROW_SUM(CSR_QUANTIZED_U8);
  prt_store_rgb3(out, row, sum * row_scales[row]);
}

// ---- a vertex subset (the frame loop's culling, docs/rendering.md "Culling") ----
//
// The rows of the vertices in vertex_ids only: work-item i sums row vertex_ids[i / dim] * dim +
// i % dim with the full kernels' row loop, so those rows get their bits; other rows of `out`
// are not written.
#define CSR_QUANTIZED_SUBSET_ROW()                      \
  const uint item = get_global_id(0);                   \
  PRT_GUARD(item, subset_rows);                         \
  const uint row = vertex_ids[item / dim] * dim + item % dim

__kernel PRT_WG_ATTR void csr_quantized_f32_vertices(
    const uint subset_rows, const uint dim, __global const uint* restrict vertex_ids,
    __global const uint* restrict offsets, __global const PRT_COLUMN_T* restrict columns,
    __global const float* restrict values, __global const float4* restrict light,
    __global float* restrict out) {
  CSR_QUANTIZED_SUBSET_ROW();
  CSR_QUANTIZED_ROW_SUM(CSR_QUANTIZED_F32);
  prt_store_rgb3(out, row, sum);
}

__kernel PRT_WG_ATTR void csr_quantized_f16_vertices(
    const uint subset_rows, const uint dim, __global const uint* restrict vertex_ids,
    __global const uint* restrict offsets, __global const PRT_COLUMN_T* restrict columns,
    __global const half* restrict values, __global const float4* restrict light,
    __global float* restrict out) {
  CSR_QUANTIZED_SUBSET_ROW();
  CSR_QUANTIZED_ROW_SUM(CSR_QUANTIZED_F16);
  prt_store_rgb3(out, row, sum);
}

__kernel PRT_WG_ATTR void csr_quantized_u8_vertices(
    const uint subset_rows, const uint dim, __global const uint* restrict vertex_ids,
    __global const uint* restrict offsets, __global const PRT_COLUMN_T* restrict columns,
    __global const uchar* restrict codes, __global const float* restrict row_scales,
    __global const float4* restrict light, __global float* restrict out) {
  CSR_QUANTIZED_SUBSET_ROW();
  CSR_QUANTIZED_ROW_SUM(CSR_QUANTIZED_U8);
  prt_store_rgb3(out, row, sum * row_scales[row]);
}
