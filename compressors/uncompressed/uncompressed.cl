// Backend `uncompressed`: L* = T L with T in CSR (u32 row offsets, u16 or u32 column ids, u8
// counts times one scale 1/s^2). Two variants; the host picks one per device
// (compressors/uncompressed/README.md):
//
//   uncompressed_rows   one work-item per row. Best on CPUs (PoCL): each work-item streams its
//                       row with four independent float4 accumulators, as the C++ loop does.
//   uncompressed_lanes  a work-group per block of rows, PRT_LANES lanes per row: lane l sums
//                       entries l, l + PRT_LANES, ... so a row's reads are coalesced on a GPU,
//                       then the lanes reduce in local memory.
//
// Host defines: PRT_COLUMN_T (ushort or uint), PRT_WG_SIZE, PRT_LANES (a power of two dividing
// PRT_WG_SIZE, lanes variant only). The light is float4 (RGB + pad); the output is packed RGB
// (3 floats per row), the layout of prt::LocalRadiance, so it is read back without a copy.

#ifndef PRT_COLUMN_T
#define PRT_COLUMN_T ushort
#endif
#ifndef PRT_LANES
#define PRT_LANES 8
#endif

__kernel PRT_WG_ATTR void uncompressed_rows(const uint rows, const float scale,
                                            __global const uint* restrict offsets,
                                            __global const PRT_COLUMN_T* restrict columns,
                                            __global const uchar* restrict counts,
                                            __global const float4* restrict light,
                                            __global float* restrict out) {
  const uint row = get_global_id(0);
  PRT_GUARD(row, rows);
  uint i = offsets[row];
  const uint end = offsets[row + 1];
  // Four independent chains: one chain would serialise on the add latency (DESIGN.md, PoCL).
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

__kernel PRT_WG_ATTR void uncompressed_lanes(const uint rows, const float scale,
                                             __global const uint* restrict offsets,
                                             __global const PRT_COLUMN_T* restrict columns,
                                             __global const uchar* restrict counts,
                                             __global const float4* restrict light,
                                             __global float* restrict out) {
  __local float4 partial[PRT_WG_SIZE];
  const uint lid = get_local_id(0);
  const uint lane = lid % PRT_LANES;
  const uint row = get_group_id(0) * (PRT_WG_SIZE / PRT_LANES) + lid / PRT_LANES;
  // Rows past the end (padding) run with an empty range: every work-item must reach every
  // barrier below, so they are masked, never returned early.
  const bool active = row < rows;
  const uint begin = active ? offsets[row] : 0u;
  const uint end = active ? offsets[row + 1] : 0u;
  float4 a0 = (float4)(0.0f), a1 = (float4)(0.0f);
  uint i = begin + lane;
  for (; i + PRT_LANES < end; i += 2 * PRT_LANES) {
    a0 += convert_float(counts[i]) * light[columns[i]];
    a1 += convert_float(counts[i + PRT_LANES]) * light[columns[i + PRT_LANES]];
  }
  if (i < end) a0 += convert_float(counts[i]) * light[columns[i]];
  partial[lid] = a0 + a1;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint stride = PRT_LANES / 2; stride > 0; stride /= 2) {
    if (lane < stride) partial[lid] += partial[lid + stride];
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  if (active && lane == 0) prt_store_rgb3(out, row, partial[lid] * scale);
}

// ---- culling (uncompressed_culled.h, docs/rendering.md "Culling") ----
//
// The sum of uncompressed_rows over the entries of the faces in `lit` only: entry i of the
// row's full chunks of four goes to accumulator (i - begin) % 4, the tail to accumulator 0,
// in increasing i, as in uncompressed_rows; the skipped entries would add count * 0 = 0, so the
// result is bit-identical. face_starts: 5 ushort per row, the first entry of faces 1..5
// relative to the row's first entry (not read when lit = 0x3f).
#define PRT_ALL_FACES 0x3fu

float4 prt_culled_row(const uint row, const float scale, __global const uint* restrict offsets,
                      __global const PRT_COLUMN_T* restrict columns,
                      __global const uchar* restrict counts,
                      __global const ushort* restrict face_starts, const uint lit,
                      __global const float4* restrict light) {
  const uint b = offsets[row];
  const uint e = offsets[row + 1];
  const uint full = b + ((e - b) & ~3u);
  float4 a[4] = {(float4)(0.0f), (float4)(0.0f), (float4)(0.0f), (float4)(0.0f)};
  uint f = 0;
  while (f < 6) {
    if (lit != PRT_ALL_FACES && ((lit >> f) & 1u) == 0) {
      ++f;
      continue;
    }
    uint g = f;
    while (g < 6 && (lit == PRT_ALL_FACES || ((lit >> g) & 1u) != 0)) ++g;
    const uint lo = f == 0 ? b : b + face_starts[row * 5 + f - 1];
    const uint hi = g == 6 ? e : b + face_starts[row * 5 + g - 1];
    f = g;
    uint i = lo;
    const uint stop = min(hi, full);
    for (; i < stop && ((i - b) & 3u) != 0; ++i)
      a[(i - b) & 3u] += convert_float(counts[i]) * light[columns[i]];
    for (; i + 4 <= stop; i += 4) {
      a[0] += convert_float(counts[i + 0]) * light[columns[i + 0]];
      a[1] += convert_float(counts[i + 1]) * light[columns[i + 1]];
      a[2] += convert_float(counts[i + 2]) * light[columns[i + 2]];
      a[3] += convert_float(counts[i + 3]) * light[columns[i + 3]];
    }
    for (; i < stop; ++i) a[(i - b) & 3u] += convert_float(counts[i]) * light[columns[i]];
    for (i = max(lo, full); i < hi; ++i) a[0] += convert_float(counts[i]) * light[columns[i]];
  }
  return ((a[0] + a[1]) + (a[2] + a[3])) * scale;
}

// Every row, the faces in `lit` only (a light with dark faces).
__kernel PRT_WG_ATTR void uncompressed_rows_faces(const uint rows, const float scale,
                                                  __global const uint* restrict offsets,
                                                  __global const PRT_COLUMN_T* restrict columns,
                                                  __global const uchar* restrict counts,
                                                  __global const ushort* restrict face_starts,
                                                  const uint lit,
                                                  __global const float4* restrict light,
                                                  __global float* restrict out) {
  const uint row = get_global_id(0);
  PRT_GUARD(row, rows);
  prt_store_rgb3(out, row,
                 prt_culled_row(row, scale, offsets, columns, counts, face_starts, lit, light));
}

// The rows of the vertices in vertex_ids only (work-item i: row vertex_ids[i / dim] * dim +
// i % dim); other rows of `out` are not written.
__kernel PRT_WG_ATTR void uncompressed_vertices(const uint subset_rows, const uint dim,
                                                __global const uint* restrict vertex_ids,
                                                const float scale,
                                                __global const uint* restrict offsets,
                                                __global const PRT_COLUMN_T* restrict columns,
                                                __global const uchar* restrict counts,
                                                __global const ushort* restrict face_starts,
                                                const uint lit,
                                                __global const float4* restrict light,
                                                __global float* restrict out) {
  const uint i = get_global_id(0);
  PRT_GUARD(i, subset_rows);
  const uint row = vertex_ids[i / dim] * dim + i % dim;
  prt_store_rgb3(out, row,
                 prt_culled_row(row, scale, offsets, columns, counts, face_starts, lit, light));
}
