// Backend `haar`: the light's 2D non-standard Haar transform per cube face, then one sparse dot
// product per row of its kept terms with the transformed light (compressors/haar/README.md).
//
//   haar_light           one work-item per coefficient: the signed sum of its support's pixels
//                        times 1/b (haar_wavelet.h), summed as four quadrant sums. No barriers
//                        and one launch; the N (log2 R + 1) reads stay in cache.
//   haar_rows_<format>   one work-item per row: four float4 accumulators combined as
//                        (a0 + a1) + (a2 + a3), the order of the C++ reference (haar_relight.cpp)
//   haar_rows_<format>_vertices   the rows of a vertex subset only (the frame loop's culling)
//   haar_columns         device option opencl_order=columns, Ng 2003's order: one work-group per
//                        block of PRT_BLOCK_ROWS rows (haar_columns.h), the block's sums in local
//                        memory; for each listed light term, the work-items add the block's
//                        entries of that column (distinct rows: no two items hit one row), then
//                        a barrier before the next column. Only the listed columns are read.
//
// Host defines: PRT_RES (R, a power of two), PRT_INDEX_T (ushort or uint), PRT_WG_SIZE,
// PRT_BLOCK_ROWS (rows a column block holds; its float4 sums must fit local memory). Lights
// are float4 (RGB + pad); the output is packed RGB (3 floats per row), prt::LocalRadiance.

#ifndef PRT_RES
#define PRT_RES 32
#endif
#ifndef PRT_INDEX_T
#define PRT_INDEX_T ushort
#endif
#ifndef PRT_BLOCK_ROWS
#define PRT_BLOCK_ROWS 2048
#endif

float4 haar_block_sum(__global const float4* restrict face, const int x0, const int y0,
                      const int size) {
  float4 s = (float4)(0.0f);
  for (int v = y0; v < y0 + size; ++v)
    for (int u = x0; u < x0 + size; ++u) s += face[v * PRT_RES + u];
  return s;
}

__kernel PRT_WG_ATTR void haar_light(const uint n, __global const float4* restrict light,
                                     __global float4* restrict coefficients) {
  const uint k = get_global_id(0);
  PRT_GUARD(k, n);
  const uint face_size = PRT_RES * PRT_RES;
  __global const float4* face = light + (k / face_size) * face_size;
  const int x = (int)(k % face_size) % PRT_RES;
  const int y = (int)(k % face_size) / PRT_RES;
  if (x == 0 && y == 0) {
    coefficients[k] = haar_block_sum(face, 0, 0, PRT_RES) * (1.0f / PRT_RES);
    return;
  }
  int level = 1;
  while (2 * level <= max(x, y)) level *= 2;
  const int size = PRT_RES / level;
  const int half_size = size / 2;
  const int split_x = x >= level, split_y = y >= level;
  const int x0 = (split_x ? x - level : x) * size;
  const int y0 = (split_y ? y - level : y) * size;
  const float4 q00 = haar_block_sum(face, x0, y0, half_size);
  const float4 q10 = haar_block_sum(face, x0 + half_size, y0, half_size);
  const float4 q01 = haar_block_sum(face, x0, y0 + half_size, half_size);
  const float4 q11 = haar_block_sum(face, x0 + half_size, y0 + half_size, half_size);
  float4 s;
  if (split_x && split_y) {
    s = (q00 - q10) - (q01 - q11);
  } else if (split_x) {
    s = (q00 - q10) + (q01 - q11);
  } else {
    s = (q00 + q10) - (q01 + q11);
  }
  coefficients[k] = s * (1.0f / size);
}

// The row loop of every rows kernel; VALUE(i) is the float multiplying W L at term i.
#define HAAR_ROW_SUM(VALUE)                                                          \
  uint i = offsets[row];                                                             \
  const uint end = offsets[row + 1];                                                 \
  float4 a0 = (float4)(0.0f), a1 = (float4)(0.0f), a2 = (float4)(0.0f),              \
         a3 = (float4)(0.0f);                                                        \
  for (; i + 4 <= end; i += 4) {                                                     \
    a0 += VALUE(i + 0) * light[indices[i + 0]];                                      \
    a1 += VALUE(i + 1) * light[indices[i + 1]];                                      \
    a2 += VALUE(i + 2) * light[indices[i + 2]];                                      \
    a3 += VALUE(i + 3) * light[indices[i + 3]];                                      \
  }                                                                                  \
  for (; i < end; ++i) a0 += VALUE(i) * light[indices[i]];                           \
  const float4 sum = (a0 + a1) + (a2 + a3)

#define HAAR_F32(i) values[i]
#define HAAR_F16(i) vload_half((i), values)
#define HAAR_S8(i) convert_float(values[i])

#define HAAR_FULL_ROW()           \
  const uint row = get_global_id(0); \
  PRT_GUARD(row, rows)
#define HAAR_SUBSET_ROW()                              \
  const uint item = get_global_id(0);                  \
  PRT_GUARD(item, subset_rows);                        \
  const uint row = vertex_ids[item / dim] * dim + item % dim

// Kernel NAME over rows picked by PICK, values of type VALUE_T read by VALUE, times the row's
// scale when SCALED.
#define HAAR_ROWS_KERNEL(NAME, PICK_ARGS, PICK, VALUE_T, VALUE, SCALED)                        \
  __kernel PRT_WG_ATTR void NAME(PICK_ARGS, __global const uint* restrict offsets,             \
                                 __global const PRT_INDEX_T* restrict indices,                 \
                                 __global const VALUE_T* restrict values,                      \
                                 __global const float* restrict row_scales,                    \
                                 __global const float4* restrict light,                        \
                                 __global float* restrict out) {                               \
    PICK();                                                                                    \
    HAAR_ROW_SUM(VALUE);                                                                       \
    prt_store_rgb3(out, row, SCALED ? sum * row_scales[row] : sum);                            \
  }

#define HAAR_FULL_ARGS const uint rows
#define HAAR_SUBSET_ARGS \
  const uint subset_rows, const uint dim, __global const uint* restrict vertex_ids

HAAR_ROWS_KERNEL(haar_rows_f32, HAAR_FULL_ARGS, HAAR_FULL_ROW, float, HAAR_F32, 0)
HAAR_ROWS_KERNEL(haar_rows_f16, HAAR_FULL_ARGS, HAAR_FULL_ROW, half, HAAR_F16, 0)
HAAR_ROWS_KERNEL(haar_rows_s8, HAAR_FULL_ARGS, HAAR_FULL_ROW, char, HAAR_S8, 1)
HAAR_ROWS_KERNEL(haar_rows_f32_vertices, HAAR_SUBSET_ARGS, HAAR_SUBSET_ROW, float, HAAR_F32, 0)
HAAR_ROWS_KERNEL(haar_rows_f16_vertices, HAAR_SUBSET_ARGS, HAAR_SUBSET_ROW, half, HAAR_F16, 0)
HAAR_ROWS_KERNEL(haar_rows_s8_vertices, HAAR_SUBSET_ARGS, HAAR_SUBSET_ROW, char, HAAR_S8, 1)

__kernel PRT_WG_ATTR void haar_columns(const uint rows, const uint cols, const uint kept_count,
                                       __global const uint* restrict kept,
                                       __global const float4* restrict light,
                                       __global const uint* restrict offsets,
                                       __global const ushort* restrict block_rows,
                                       __global const float* restrict values,
                                       __global const float* restrict row_scales,
                                       const uint scaled, __global float* restrict out) {
  __local float4 acc[PRT_BLOCK_ROWS];
  const uint lid = get_local_id(0);
  const uint first = get_group_id(0) * PRT_BLOCK_ROWS;
  const uint count = min((uint)PRT_BLOCK_ROWS, rows - first);
  for (uint r = lid; r < count; r += PRT_WG_SIZE) acc[r] = (float4)(0.0f);
  barrier(CLK_LOCAL_MEM_FENCE);
  __global const uint* off = offsets + (size_t)get_group_id(0) * (cols + 1);
  for (uint t = 0; t < kept_count; ++t) {
    const uint j = kept[t];
    const float4 l = light[j];
    const uint end = off[j + 1];
    for (uint e = off[j] + lid; e < end; e += PRT_WG_SIZE) acc[block_rows[e]] += values[e] * l;
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  for (uint r = lid; r < count; r += PRT_WG_SIZE)
    prt_store_rgb3(out, first + r, scaled ? acc[r] * row_scales[first + r] : acc[r]);
}
