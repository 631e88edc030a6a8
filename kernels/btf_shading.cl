// BTF shading (eq. 3 of Sun et al.; core/include/prtlab/render/btf_shading.h, docs/rendering.md):
//
//   B(x, e) = sum_j b(u, e, d_j) * L*_j(x),   L*(x) = b0 L*_p0 + b1 L*_p1 + b2 L*_p2
//
// The last file of a shading program: kernels/btf_lookup.cl and the material's source (the
// material contract of compress/material_compressor.h: prt_material, prt_material_begin,
// prt_material_chunk, prt_material_one, PRT_MATERIAL_PARAMS / PRT_MATERIAL_ARGS) come first, so
// these kernels shade with any material.
//
//   btf_shade_single  one work-item per pixel: the material's b(u, e, .) for the pixel, L* of the
//                     triangle's 3 vertices, the dot product; misses copy the background pixel
//                     the host chose
//   btf_view_cache    one work-item per hit pixel ("slot"): b(u, e, .), stored
//   btf_shade_cached  one work-item per hit pixel: the dot product of the cached b(u, e) with the
//                     interpolated L*, written to the slot's pixel (a light change: the misses
//                     keep what btf_shade_misses wrote)
//   btf_view_cache_shade  one work-item per hit pixel: b(u, e, .) stored as btf_view_cache does
//                     and, in the same pass, its dot product with L* written to the slot's pixel
//                     (a view change: the cache is not read back)
//   btf_slot_view_samples  one work-item per 16 hit pixels: their view samples, for a material
//                     that takes them precomputed (PRT_MATERIAL_SLOT_VIEWS)
//   btf_shade_misses  one work-item per pixel: misses copy their background pixel, hits are left
//                     to btf_view_cache_shade
//
// Data (all packed float RGB, no padding):
//   radiance   L*, vertex * 3M + 3 j + c
//   cache      b(u, e), slot * 3M + 3 j + c
//   code       per pixel: slot >= 0 for a hit, -(1 + k) for a miss showing background pixel k
//              (the host appends a black pixel for "no background")
//   slot_ids   (triangle, part); slot_geom (b1, b2, u, v); slot_view (e.t, e.b, e.n, 0);
//              slot_pixel the pixel of each slot
//
// Vector loop: the 3M floats of b(u, e) and of L* are walked 12 at a time (4 lights, 3 float4
// loads, no padding); products accumulate in three float4s whose lanes hold the channels in the
// pattern rgbr gbrg brgb, summed per channel at the end. 3M % 12 floats (odd S: M = 1 mod 4)
// are done one at a time.

// Sum of 12 floats' products split back into channels (lanes rgbr gbrg brgb).
float3 prt_channels(float4 a0, float4 a1, float4 a2) {
  return (float3)(a0.x + a0.w + a1.z + a2.y, a0.y + a1.x + a1.w + a2.z, a0.z + a1.y + a2.x + a2.w);
}

// The L* rows l0, l1, l2 of triangle `tri`'s vertices and their weights w0, w1, w2 (from the
// slot's (b1, b2, u, v)), which PRT_LSTAR4 and PRT_LSTAR1 read.
#define PRT_TRIANGLE_LSTAR(tri, geom)                             \
  const uint3 v = vload3((uint)(tri), indices);                   \
  __global const float* l0 = radiance + (ulong)v.x * PRT_CH;      \
  __global const float* l1 = radiance + (ulong)v.y * PRT_CH;      \
  __global const float* l2 = radiance + (ulong)v.z * PRT_CH;      \
  const float w1 = (geom).x, w2 = (geom).y, w0 = 1.0f - w1 - w2

// L*(x) for 12 floats: the triangle's three vertex vectors weighted by the barycentrics.
#define PRT_LSTAR4(k) \
  (w0 * vload4((k), l0 + c) + w1 * vload4((k), l1 + c) + w2 * vload4((k), l2 + c))
#define PRT_LSTAR1 (w0 * l0[c] + w1 * l1[c] + w2 * l2[c])

// ---- kernels ---------------------------------------------------------------------------------

__kernel PRT_WG_ATTR void btf_shade_single(
    const uint pixels, __global const int* restrict code, __global const int2* restrict slot_ids,
    __global const float4* restrict slot_geom, __global const float4* restrict slot_view,
    __global const uint* restrict indices, __global const float* restrict radiance,
    __global const float* restrict background,
    __global float* restrict image PRT_MATERIAL_PARAMS) {
  const uint i = get_global_id(0);
  PRT_GUARD(i, pixels);
  const int s = code[i];
  if (s < 0) {
    vstore3(vload3((uint)(-(s + 1)), background), i, image);
    return;
  }
  const int2 ids = slot_ids[s];
  const float4 geom = slot_geom[s];
  PRT_TRIANGLE_LSTAR(ids.x, geom);

  prt_material mat;
  prt_material_begin(&mat, ids.y, geom.zw, slot_view[s].xyz PRT_MATERIAL_ARGS);
  float4 a0 = (float4)(0.0f), a1 = (float4)(0.0f), a2 = (float4)(0.0f);
  for (int c = 0; c < PRT_CH12; c += 12) {
    float4 b0, b1, b2;
    prt_material_chunk(&mat, c, &b0, &b1, &b2 PRT_MATERIAL_ARGS);
    a0 += b0 * PRT_LSTAR4(0);
    a1 += b1 * PRT_LSTAR4(1);
    a2 += b2 * PRT_LSTAR4(2);
  }
  float3 rgb = prt_channels(a0, a1, a2);
  float tail[3] = {0.0f, 0.0f, 0.0f};
  for (int c = PRT_CH12; c < PRT_CH; ++c)
    tail[c % 3] += prt_material_one(&mat, c PRT_MATERIAL_ARGS) * PRT_LSTAR1;
  rgb += (float3)(tail[0], tail[1], tail[2]);
  vstore3(rgb, i, image);
}

__kernel PRT_WG_ATTR void btf_view_cache(const uint slots, __global const int2* restrict slot_ids,
                                         __global const float4* restrict slot_geom,
                                         __global const float4* restrict slot_view,
                                         __global float* restrict cache PRT_MATERIAL_PARAMS) {
  const uint s = get_global_id(0);
  PRT_GUARD(s, slots);
  const int2 ids = slot_ids[s];
  prt_material mat;
  prt_material_begin(&mat, ids.y, slot_geom[s].zw, slot_view[s].xyz PRT_MATERIAL_ARGS);
  __global float* out = cache + (ulong)s * PRT_CH;
  for (int c = 0; c < PRT_CH12; c += 12) {
    float4 b0, b1, b2;
    prt_material_chunk(&mat, c, &b0, &b1, &b2 PRT_MATERIAL_ARGS);
    vstore4(b0, 0, out + c);
    vstore4(b1, 1, out + c);
    vstore4(b2, 2, out + c);
  }
  for (int c = PRT_CH12; c < PRT_CH; ++c) out[c] = prt_material_one(&mat, c PRT_MATERIAL_ARGS);
}

// A light change: only the hit pixels change, so the work-items are the slots (the misses keep
// what btf_shade_misses wrote after the view pass); the pixel is written through slot_pixel.
__kernel PRT_WG_ATTR void btf_shade_cached(
    const uint slots, __global const int2* restrict slot_ids,
    __global const float4* restrict slot_geom, __global const uint* restrict slot_pixel,
    __global const uint* restrict indices, __global const float* restrict radiance,
    __global const float* restrict cache, __global float* restrict image) {
  const uint s = get_global_id(0);
  PRT_GUARD(s, slots);
  const float4 geom = slot_geom[s];
  PRT_TRIANGLE_LSTAR(slot_ids[s].x, geom);
  __global const float* b = cache + (ulong)s * PRT_CH;
  float4 a0 = (float4)(0.0f), a1 = (float4)(0.0f), a2 = (float4)(0.0f);
  for (int c = 0; c < PRT_CH12; c += 12) {
    a0 += vload4(0, b + c) * PRT_LSTAR4(0);
    a1 += vload4(1, b + c) * PRT_LSTAR4(1);
    a2 += vload4(2, b + c) * PRT_LSTAR4(2);
  }
  float3 rgb = prt_channels(a0, a1, a2);
  float tail[3] = {0.0f, 0.0f, 0.0f};
  for (int c = PRT_CH12; c < PRT_CH; ++c) tail[c % 3] += b[c] * PRT_LSTAR1;
  rgb += (float3)(tail[0], tail[1], tail[2]);
  vstore3(rgb, slot_pixel[s], image);
}

// The view samples of 16 hit pixels a work-item on their parts' view grids (part_view_side; 0:
// none), for a material that takes them (PRT_MATERIAL_SLOT_VIEWS): prt_view_samples16, vector
// code where the view-change kernel would run prt_view_samples one pixel at a time.
__kernel PRT_WG_ATTR void btf_slot_view_samples(const uint slots,
                                                __global const int2* restrict slot_ids,
                                                __global const float4* restrict slot_view,
                                                __global const int* restrict part_view_side,
                                                __global int4* restrict slot_views,
                                                __global float4* restrict slot_view_w) {
  const uint first = get_global_id(0) * 16;
  PRT_GUARD(first, slots);
  float x[16], y[16], z[16];
  int side[16];
  for (int i = 0; i < 16; ++i) {
    const uint s = min(first + (uint)i, slots - 1);
    const float4 e = slot_view[s];
    x[i] = e.x;
    y[i] = e.y;
    z[i] = e.z;
    side[i] = max(part_view_side[slot_ids[s].y], 1);
  }
  int16 views[4];
  float16 weights[4];
  prt_view_samples16(vload16(0, side), vload16(0, x), vload16(0, y), vload16(0, z), views,
                     weights);
  int v[4][16];
  float w[4][16];
  for (int k = 0; k < 4; ++k) {
    vstore16(views[k], 0, v[k]);
    vstore16(weights[k], 0, w[k]);
  }
  for (int i = 0; i < 16 && first + (uint)i < slots; ++i) {
    slot_views[first + i] = (int4)(v[0][i], v[1][i], v[2][i], v[3][i]);
    slot_view_w[first + i] = (float4)(w[0][i], w[1][i], w[2][i], w[3][i]);
  }
}

// The first argument after slot_view_w is the material's (kViewCacheShadeMaterialArg);
// slot_views and slot_view_w are read only by a material with PRT_MATERIAL_SLOT_VIEWS. The dot
// product is btf_shade_cached's, on the values it would read back from `cache`, in its order.
__kernel PRT_WG_ATTR void btf_view_cache_shade(
    const uint slots, __global const int2* restrict slot_ids,
    __global const float4* restrict slot_geom, __global const float4* restrict slot_view,
    __global const uint* restrict slot_pixel, __global const uint* restrict indices,
    __global const float* restrict radiance, __global float* restrict image,
    __global float* restrict cache, __global const int4* restrict slot_views,
    __global const float4* restrict slot_view_w PRT_MATERIAL_PARAMS) {
  const uint s = get_global_id(0);
  PRT_GUARD(s, slots);
#ifdef PRT_PROBE_LAUNCH_ONLY
  vstore3((float3)(slot_geom[s].x), slot_pixel[s], image);
  return;
#endif
  const int2 ids = slot_ids[s];
  const float4 geom = slot_geom[s];
  prt_material mat;
#ifdef PRT_MATERIAL_SLOT_VIEWS
  prt_material_begin_views(&mat, ids.y, geom.zw, slot_views[s], slot_view_w[s] PRT_MATERIAL_ARGS);
#else
  prt_material_begin(&mat, ids.y, geom.zw, slot_view[s].xyz PRT_MATERIAL_ARGS);
#endif
  PRT_TRIANGLE_LSTAR(ids.x, geom);
  __global float* out = cache + (ulong)s * PRT_CH;
  float4 a0 = (float4)(0.0f), a1 = (float4)(0.0f), a2 = (float4)(0.0f);
  for (int c = 0; c < PRT_CH12; c += 12) {
    float4 b0, b1, b2;
#ifdef PRT_PROBE_NO_VECTOR_READS
    // The material's first word stands in, so that its begin (the view samples) is still done.
    b0 = b1 = b2 = (float4)((float)c + (float)(*(const uint*)&mat));
#else
    prt_material_chunk(&mat, c, &b0, &b1, &b2 PRT_MATERIAL_ARGS);
#endif
#ifndef PRT_PROBE_NO_CACHE_WRITES
    vstore4(b0, 0, out + c);
    vstore4(b1, 1, out + c);
    vstore4(b2, 2, out + c);
#endif
    a0 += b0 * PRT_LSTAR4(0);
    a1 += b1 * PRT_LSTAR4(1);
    a2 += b2 * PRT_LSTAR4(2);
  }
  float3 rgb = prt_channels(a0, a1, a2);
  float tail[3] = {0.0f, 0.0f, 0.0f};
  for (int c = PRT_CH12; c < PRT_CH; ++c) {
    const float b = prt_material_one(&mat, c PRT_MATERIAL_ARGS);
    out[c] = b;
    tail[c % 3] += b * PRT_LSTAR1;
  }
  rgb += (float3)(tail[0], tail[1], tail[2]);
  vstore3(rgb, slot_pixel[s], image);
}

__kernel PRT_WG_ATTR void btf_shade_misses(const uint pixels, __global const int* restrict code,
                                           __global const float* restrict background,
                                           __global float* restrict image) {
  const uint i = get_global_id(0);
  PRT_GUARD(i, pixels);
  const int s = code[i];
  if (s < 0) vstore3(vload3((uint)(-(s + 1)), background), i, image);
}
