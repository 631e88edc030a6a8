// Backend `bicluster`: L* = sum_i B_i L in two kernels (Algorithm 2 of Sun et al.; layout in
// compressors/bicluster/bicluster.h and compressors/bicluster/README.md):
//
//   bicluster_phase1   one work-item per bicluster: P_i = sum_m t_m L[k_m] (float4 RGB; zero
//                      slots have no columns: 0); the extra work-item i = B zeroes the zero slot
//                      at or above B, which pads lanes
//   bicluster_phase2   one work-item per slice of 4 rows (SELL-4, rows in phase 2's row order):
//                      a fixed-length loop over the slice's steps, each lane adding its u16
//                      delta to its id and then P_id (one accumulator per row), then each row
//                      times 1/s^2 to its place in the output
//   bicluster_phase2_ids  the same over u32 ids expanded at upload (opencl_ids=u32)
//   bicluster_phase2_subset, bicluster_phase2_ids_subset
//                      the same over a list of slices, storing only the listed lanes (a vertex
//                      subset, bicluster_culling.h)
//
// Host defines: PRT_COLUMN_T (ushort or uint), PRT_WG_SIZE.
// Constants are signed 16-bit counts. The light and P are float4 (RGB + pad); the output is
// packed RGB.

#ifndef PRT_COLUMN_T
#define PRT_COLUMN_T ushort
#endif
#ifndef PRT_PHASE1_PER_ITEM
#define PRT_PHASE1_PER_ITEM 8
#endif

// faces: per bicluster, bit f set when one of its columns lies on cube face f; a bicluster with
// no column on a face in `lit` (the faces the light does not leave dark) has P = +0 exactly and
// is not read (bicluster_culling.h).
__kernel PRT_WG_ATTR void bicluster_phase1(const uint biclusters, const uint last_zero,
                                           __global const uint* restrict col_offsets,
                                           __global const PRT_COLUMN_T* restrict columns,
                                           __global const short* restrict constants,
                                           __global const uchar* restrict faces, const uint lit,
                                           __global const float4* restrict light,
                                           __global float4* restrict products) {
  // PRT_PHASE1_PER_ITEM consecutive biclusters per work-item: fewer, longer work-items (a
  // bicluster is one or two multiply-adds, less than PoCL's per-work-item cost).
  const uint first = get_global_id(0) * PRT_PHASE1_PER_ITEM;
  PRT_GUARD(first, biclusters + 1);
  if (get_global_id(0) == 0) products[last_zero] = (float4)(0.0f);
  const uint stop = min(first + PRT_PHASE1_PER_ITEM, biclusters);
  for (uint i = first; i < stop; ++i) {
    const uint end = col_offsets[i + 1];
    float4 a = (float4)(0.0f);
    if ((faces[i] & lit) != 0) {
      for (uint q = col_offsets[i]; q < end; ++q)
        a += convert_float(constants[q]) * light[columns[q]];
    }
    products[i] = a;
  }
}

// The rows of slice s whose lane bit is set in `lanes` (lanes holding row `rows` are padding),
// times 1/s^2.
void prt_store_slice(const uint s, const uint lanes, const uint rows, const float scale,
                     __global const uint* restrict slice_rows, const float4 a0, const float4 a1,
                     const float4 a2, const float4 a3, __global float* restrict out) {
  const uint4 r = vload4(s, slice_rows);
  if (r.s0 < rows && (lanes & 1u)) prt_store_rgb3(out, r.s0, a0 * scale);
  if (r.s1 < rows && (lanes & 2u)) prt_store_rgb3(out, r.s1, a1 * scale);
  if (r.s2 < rows && (lanes & 4u)) prt_store_rgb3(out, r.s2, a2 * scale);
  if (r.s3 < rows && (lanes & 8u)) prt_store_rgb3(out, r.s3, a3 * scale);
}

// Phase 2 of slice s over the u16 deltas, storing the lanes in `lanes`.
void prt_phase2_codes(const uint s, const uint lanes, const uint rows, const float scale,
                      __global const uint* restrict slice_offsets,
                      __global const uint* restrict slice_rows,
                      __global const uint* restrict slice_base, __global const ushort* restrict codes,
                      __global const float4* restrict products, __global float* restrict out) {
  float4 a0 = (float4)(0.0f), a1 = (float4)(0.0f), a2 = (float4)(0.0f), a3 = (float4)(0.0f);
  uint i0 = slice_base[s], i1 = i0, i2 = i0, i3 = i0;
  const uint end = slice_offsets[s + 1];
  // A step's four u16 codes are one aligned 8-byte word (offsets are multiples of 4).
  __global const ulong* steps = (__global const ulong*)codes;
  for (uint q = slice_offsets[s] / 4; q < end / 4; ++q) {
    const ulong c = steps[q];
    i0 += (uint)(c & 0xffffu);
    i1 += (uint)((c >> 16) & 0xffffu);
    i2 += (uint)((c >> 32) & 0xffffu);
    i3 += (uint)(c >> 48);
    a0 += products[i0];
    a1 += products[i1];
    a2 += products[i2];
    a3 += products[i3];
  }
  prt_store_slice(s, lanes, rows, scale, slice_rows, a0, a1, a2, a3, out);
}

// The same over u32 ids expanded at upload.
void prt_phase2_ids(const uint s, const uint lanes, const uint rows, const float scale,
                    __global const uint* restrict slice_offsets,
                    __global const uint* restrict slice_rows, __global const uint* restrict ids,
                    __global const float4* restrict products, __global float* restrict out) {
  float4 a0 = (float4)(0.0f), a1 = (float4)(0.0f), a2 = (float4)(0.0f), a3 = (float4)(0.0f);
  const uint end = slice_offsets[s + 1];
  for (uint q = slice_offsets[s]; q < end; q += 4) {
    const uint4 id = vload4(0, ids + q);
    a0 += products[id.s0];
    a1 += products[id.s1];
    a2 += products[id.s2];
    a3 += products[id.s3];
  }
  prt_store_slice(s, lanes, rows, scale, slice_rows, a0, a1, a2, a3, out);
}

__kernel PRT_WG_ATTR void bicluster_phase2(const uint slices, const uint rows, const float scale,
                                           __global const uint* restrict slice_offsets,
                                           __global const uint* restrict slice_rows,
                                           __global const uint* restrict slice_base,
                                           __global const ushort* restrict codes,
                                           __global const float4* restrict products,
                                           __global float* restrict out) {
  const uint s = get_global_id(0);
  PRT_GUARD(s, slices);
  prt_phase2_codes(s, 0xfu, rows, scale, slice_offsets, slice_rows, slice_base, codes, products,
                   out);
}

// The same with the lanes' ids expanded to u32 at upload (opencl_ids=u32): no decoding.
__kernel PRT_WG_ATTR void bicluster_phase2_ids(const uint slices, const uint rows,
                                               const float scale,
                                               __global const uint* restrict slice_offsets,
                                               __global const uint* restrict slice_rows,
                                               __global const uint* restrict ids,
                                               __global const float4* restrict products,
                                               __global float* restrict out) {
  const uint s = get_global_id(0);
  PRT_GUARD(s, slices);
  prt_phase2_ids(s, 0xfu, rows, scale, slice_offsets, slice_rows, ids, products, out);
}

// A vertex subset (bicluster_culling.h): work-item i runs slice subset[i] and stores the lanes
// in lanes[i]; the other rows of `out` are not written.
__kernel PRT_WG_ATTR void bicluster_phase2_subset(
    const uint count, __global const uint* restrict subset, __global const uchar* restrict lanes,
    const uint rows, const float scale, __global const uint* restrict slice_offsets,
    __global const uint* restrict slice_rows, __global const uint* restrict slice_base,
    __global const ushort* restrict codes, __global const float4* restrict products,
    __global float* restrict out) {
  const uint i = get_global_id(0);
  PRT_GUARD(i, count);
  prt_phase2_codes(subset[i], lanes[i], rows, scale, slice_offsets, slice_rows, slice_base, codes,
                   products, out);
}

__kernel PRT_WG_ATTR void bicluster_phase2_ids_subset(
    const uint count, __global const uint* restrict subset, __global const uchar* restrict lanes,
    const uint rows, const float scale, __global const uint* restrict slice_offsets,
    __global const uint* restrict slice_rows, __global const uint* restrict ids,
    __global const float4* restrict products, __global float* restrict out) {
  const uint i = get_global_id(0);
  PRT_GUARD(i, count);
  prt_phase2_ids(subset[i], lanes[i], rows, scale, slice_offsets, slice_rows, ids, products, out);
}
