// BTF shading (eq. 3 of Sun et al.; core/include/prtlab/render/btf_shading.h, docs/rendering.md):
//
//   B(x, e) = sum_j b(u, e, d_j) * L*_j(x),   L*(x) = b0 L*_p0 + b1 L*_p1 + b2 L*_p2
//
//   btf_shade_single  one work-item per pixel: texel(s) and 4 view samples of the part's BTF,
//                     L* of the triangle's 3 vertices, the dot product; misses copy the
//                     background pixel the host chose
//   btf_view_cache    one work-item per hit pixel ("slot"): b(u, e, .) = the weighted sum of
//                     the BTF's 4 (nearest) or 16 (bilinear) texel x view vectors, stored
//   btf_shade_cached  one work-item per pixel: the dot product of the cached b(u, e) with the
//                     interpolated L*
//
// Host defines: PRT_M (light directions M), PRT_BILINEAR (0 nearest, 1 bilinear texels),
// PRT_WG_SIZE. Data (all packed float RGB, no padding):
//   btf        every part's BTF, rgb[((texel * V + view) * M + light) * 3 + c] from the part's
//              offset (floats); part_info = (U, view_side, view_independent, 0)
//   radiance   L*, vertex * 3M + 3 j + c
//   cache      b(u, e), slot * 3M + 3 j + c
//   code       per pixel: slot >= 0 for a hit, -(1 + k) for a miss showing background pixel k
//              (the host appends a black pixel for "no background")
//   slot_ids   (triangle, part); slot_geom (b1, b2, u, v); slot_view (e.t, e.b, e.n, 0)
//
// Vector loop: the 3M floats of a (texel, view) vector and of L* are walked 12 at a time (4
// lights, 3 float4 loads, no padding); products accumulate in three float4s whose lanes hold
// the channels in the pattern rgbr gbrg brgb, summed per channel at the end. 3M % 12 floats
// (odd S: M = 1 mod 4) are done one at a time.

#ifndef PRT_M
#define PRT_M 64
#endif
#ifndef PRT_BILINEAR
#define PRT_BILINEAR 0
#endif
#define PRT_CH (3 * PRT_M)
#define PRT_CH12 (PRT_CH - PRT_CH % 12)
#if PRT_BILINEAR
#define PRT_PAIRS 16
#else
#define PRT_PAIRS 4
#endif

#define PRT_PI_F 3.14159265358979323846f
#define PRT_QUARTER_PI_F (0.25f * PRT_PI_F)

// ---- the float concentric map of core/src/btf/btf.cpp --------------------------------------------
// Ported line by line except for sin, cos and atan2, which are branch-free polynomials here:
// PoCL calls its library's versions one work-item at a time, and they were 80 % of the
// view-cache kernel's time (results/bench/shading-pocl.md).

// sin and cos of t in [-pi/4, pi/4]: Taylor series to t^11 / t^12 (truncation below 2e-9, so
// float rounding dominates); branch-free, so PoCL vectorises it across work-items, which it
// does not do for the library's sin and cos.
float2 prt_sincos_quarter(float t) {
  const float t2 = t * t;
  const float s =
      t *
      (1.0f -
       t2 / 6.0f *
           (1.0f - t2 / 20.0f * (1.0f - t2 / 42.0f * (1.0f - t2 / 72.0f * (1.0f - t2 / 110.0f)))));
  const float c =
      1.0f -
      t2 / 2.0f *
          (1.0f - t2 / 12.0f * (1.0f - t2 / 30.0f * (1.0f - t2 / 56.0f * (1.0f - t2 / 90.0f))));
  return (float2)(s, c);
}

float3 prt_square_to_hemisphere(float a, float b) {
  const float u = 2.0f * a - 1.0f, v = 2.0f * b - 1.0f;
  if (u == 0.0f && v == 0.0f) return (float3)(0.0f, 0.0f, 1.0f);
  // phi = pi/4 (v/u) in the sectors |u| > |v|, else pi/2 - pi/4 (u/v), where cos and sin swap.
  const bool horizontal = fabs(u) > fabs(v);
  const float r = horizontal ? u : v;
  const float2 sc = prt_sincos_quarter(PRT_QUARTER_PI_F * (horizontal ? v / u : u / v));
  const float cos_phi = horizontal ? sc.y : sc.x, sin_phi = horizontal ? sc.x : sc.y;
  const float r2 = fmin(r * r, 1.0f);
  const float f = sqrt(2.0f - r2);
  return (float3)(r * cos_phi * f, r * sin_phi * f, 1.0f - r2);
}

// atan(z) for |z| <= 1 (Cephes atanf: one range reduction at tan(pi/8), then a degree-9 odd
// polynomial; relative error about 2e-7). Branch-free like prt_sincos_quarter.
float prt_atan_unit(float z) {
  const float az = fabs(z);
  const bool big = az > 0.41421356237f;
  const float x = big ? (az - 1.0f) / (az + 1.0f) : az;
  const float x2 = x * x;
  const float p = (((8.05374449538e-2f * x2 - 1.38776856032e-1f) * x2 + 1.99777106478e-1f) * x2 -
                   3.33329491539e-1f) *
                      x2 * x +
                  x;
  return copysign((big ? PRT_QUARTER_PI_F : 0.0f) + p, z);
}

// hemisphere_to_square_f without atan2: the sector of phi is the octant pair of (x, y), and
// phi's offset from the sector's centre line is atan(y/x) or atan(x/y), |ratio| <= 1.
float2 prt_hemisphere_to_square(float3 d) {
  const float inv = 1.0f / sqrt(1.0f + fabs(d.z));
  const float x = d.x * inv, y = d.y * inv;
  const float r = sqrt(x * x + y * y);
  if (r == 0.0f) return (float2)(0.5f, 0.5f);
  float u, v;
  if (fabs(x) >= fabs(y)) {  // phi in [-pi/4, pi/4] or [3pi/4, 5pi/4]
    u = x > 0.0f ? r : -r;
    v = prt_atan_unit(y / x) / PRT_QUARTER_PI_F * u;
  } else {  // phi in (pi/4, 3pi/4) or (5pi/4, 7pi/4)
    v = y > 0.0f ? r : -r;
    u = prt_atan_unit(x / y) / PRT_QUARTER_PI_F * v;
  }
  return (float2)(0.5f * (u + 1.0f), 0.5f * (v + 1.0f));
}

float3 prt_clamp_to_hemisphere(float3 d) {
  if (!isfinite(d.x) || !isfinite(d.y) || !isfinite(d.z)) return (float3)(0.0f, 0.0f, 1.0f);
  if (d.x == 0.0f && d.y == 0.0f)
    return d.z < 0.0f ? (float3)(1.0f, 0.0f, 0.0f) : (float3)(0.0f, 0.0f, 1.0f);
  d.z = fmax(d.z, 0.0f);
  return normalize(d);
}

float prt_sample_centre(int i, int side) {
  return ((float)i + 0.5f) / (float)side;
}

float prt_sphere_fraction(float3 e, float3 p0, float3 p1) {
  const float d0 = length(e - p0), d1 = length(e - p1);
  const float sum = d0 + d1;
  return sum > 0.0f ? d0 / sum : 0.0f;
}

// The 4 corners (x0, y0), (x1, y0), (x0, y1), (x1, y1) of a grid with row length `stride` and
// their bilinear weights for fractions (tx, ty): the order of Btf::texel_samples and
// btf_view_samples.
void prt_bilinear_corners(int x0, int x1, int y0, int y1, int stride, float tx, float ty,
                          int* index, float* weight) {
  index[0] = y0 * stride + x0;
  index[1] = y0 * stride + x1;
  index[2] = y1 * stride + x0;
  index[3] = y1 * stride + x1;
  weight[0] = (1.0f - tx) * (1.0f - ty);
  weight[1] = tx * (1.0f - ty);
  weight[2] = (1.0f - tx) * ty;
  weight[3] = tx * ty;
}

// btf_view_samples (btf.h): the 4 view samples around e and their weights, measured on the
// sphere.
void prt_view_samples(int side, float3 view, int* views, float* weights) {
  const float3 e = prt_clamp_to_hemisphere(view);
  const float2 ab = prt_hemisphere_to_square(e);
  const int ix = (int)floor(ab.x * (float)side - 0.5f);
  const int iy = (int)floor(ab.y * (float)side - 0.5f);
  const int x0 = clamp(ix, 0, side - 1), x1 = clamp(ix + 1, 0, side - 1);
  const int y0 = clamp(iy, 0, side - 1), y1 = clamp(iy + 1, 0, side - 1);
  float tx = 0.0f, ty = 0.0f;
  if (x0 != x1)
    tx = prt_sphere_fraction(e, prt_square_to_hemisphere(prt_sample_centre(x0, side), ab.y),
                             prt_square_to_hemisphere(prt_sample_centre(x1, side), ab.y));
  if (y0 != y1)
    ty = prt_sphere_fraction(e, prt_square_to_hemisphere(ab.x, prt_sample_centre(y0, side)),
                             prt_square_to_hemisphere(ab.x, prt_sample_centre(y1, side)));
  prt_bilinear_corners(x0, x1, y0, y1, side, tx, ty, views, weights);
}

// x mod 1 in [0, 1]; 0 for a non-finite x (as btf.cpp's fract, not OpenCL's fract()).
float prt_fract(float x) {
  const float f = x - floor(x);
  return isfinite(f) ? f : 0.0f;
}

int prt_wrap(int i, int n) {
  const int r = i % n;
  return r < 0 ? r + n : r;
}

// The (texel, view) vectors of a hit and their weights (Btf::texel_samples x btf_view_samples,
// texel outer, view inner, zero weights dropped). Returns how many; offsets are in floats.
int prt_btf_pairs(ulong base, int4 info, float2 uv, float3 view, ulong* offsets, float* weights) {
  const int res = info.x, side = info.y;
  int texels[4];
  float texel_w[4];
#if PRT_BILINEAR
  const int texel_count = 4;
  const float fx = prt_fract(uv.x) * (float)res - 0.5f, fy = prt_fract(uv.y) * (float)res - 0.5f;
  const float x0f = floor(fx), y0f = floor(fy);
  const float tx = fx - x0f, ty = fy - y0f;
  const int x0 = prt_wrap((int)x0f, res), x1 = prt_wrap(x0 + 1, res);
  const int y0 = prt_wrap((int)y0f, res), y1 = prt_wrap(y0 + 1, res);
  prt_bilinear_corners(x0, x1, y0, y1, res, tx, ty, texels, texel_w);
#else
  const int texel_count = 1;
  const int x = min((int)(prt_fract(uv.x) * (float)res), res - 1);
  const int y = min((int)(prt_fract(uv.y) * (float)res), res - 1);
  texels[0] = y * res + x;
  texel_w[0] = 1.0f;
#endif
  int views[4];
  float view_w[4];
  int view_count = 4;
  if (info.z) {
    // Every view holds the same values (Btf::view_independent): one vector per texel.
    views[0] = 0;
    view_w[0] = 1.0f;
    view_count = 1;
  } else {
    prt_view_samples(side, view, views, view_w);
  }
  const ulong vcount = (ulong)side * (ulong)side;
  int n = 0;
  for (int t = 0; t < texel_count; ++t) {
    for (int k = 0; k < view_count; ++k) {
      const float w = texel_w[t] * view_w[k];
      if (w == 0.0f) continue;
      offsets[n] = base + ((ulong)texels[t] * vcount + (ulong)views[k]) * (ulong)PRT_CH;
      weights[n] = w;
      ++n;
    }
  }
  return n;
}

// Sum of 12 floats' products split back into channels (lanes rgbr gbrg brgb).
float3 prt_channels(float4 a0, float4 a1, float4 a2) {
  return (float3)(a0.x + a0.w + a1.z + a2.y, a0.y + a1.x + a1.w + a2.z, a0.z + a1.y + a2.x + a2.w);
}

// One 12-float chunk of the weighted sum of the pairs' vectors.
void prt_interp_chunk(__global const float* restrict btf, const ulong* offsets,
                      const float* weights, int n, int c, float4* b0, float4* b1, float4* b2) {
  float4 s0 = (float4)(0.0f), s1 = (float4)(0.0f), s2 = (float4)(0.0f);
  for (int p = 0; p < n; ++p) {
    __global const float* q = btf + offsets[p] + c;
    const float w = weights[p];
    s0 += w * vload4(0, q);
    s1 += w * vload4(1, q);
    s2 += w * vload4(2, q);
  }
  *b0 = s0;
  *b1 = s1;
  *b2 = s2;
}

float prt_interp_one(__global const float* restrict btf, const ulong* offsets, const float* weights,
                     int n, int c) {
  float s = 0.0f;
  for (int p = 0; p < n; ++p) s += weights[p] * btf[offsets[p] + c];
  return s;
}

// L*(x) for 12 floats: the triangle's three vertex vectors weighted by the barycentrics.
#define PRT_LSTAR4(k) \
  (w0 * vload4((k), l0 + c) + w1 * vload4((k), l1 + c) + w2 * vload4((k), l2 + c))
#define PRT_LSTAR1 (w0 * l0[c] + w1 * l1[c] + w2 * l2[c])

// ---- kernels ---------------------------------------------------------------------------------

__kernel PRT_WG_ATTR void btf_shade_single(
    const uint pixels, __global const int* restrict code, __global const int2* restrict slot_ids,
    __global const float4* restrict slot_geom, __global const float4* restrict slot_view,
    __global const uint* restrict indices, __global const float* restrict radiance,
    __global const float* restrict btf, __global const ulong* restrict part_offset,
    __global const int4* restrict part_info, __global const float* restrict background,
    __global float* restrict image) {
  const uint i = get_global_id(0);
  PRT_GUARD(i, pixels);
  const int s = code[i];
  if (s < 0) {
    vstore3(vload3((uint)(-(s + 1)), background), i, image);
    return;
  }
  const int2 ids = slot_ids[s];
  const float4 geom = slot_geom[s];
  const uint3 v = vload3((uint)ids.x, indices);
  __global const float* l0 = radiance + (ulong)v.x * PRT_CH;
  __global const float* l1 = radiance + (ulong)v.y * PRT_CH;
  __global const float* l2 = radiance + (ulong)v.z * PRT_CH;
  const float w1 = geom.x, w2 = geom.y, w0 = 1.0f - w1 - w2;

  ulong offsets[PRT_PAIRS];
  float weights[PRT_PAIRS];
  const int n = prt_btf_pairs(part_offset[ids.y], part_info[ids.y], geom.zw, slot_view[s].xyz,
                              offsets, weights);
  float4 a0 = (float4)(0.0f), a1 = (float4)(0.0f), a2 = (float4)(0.0f);
  for (int c = 0; c < PRT_CH12; c += 12) {
    float4 b0, b1, b2;
    prt_interp_chunk(btf, offsets, weights, n, c, &b0, &b1, &b2);
    a0 += b0 * PRT_LSTAR4(0);
    a1 += b1 * PRT_LSTAR4(1);
    a2 += b2 * PRT_LSTAR4(2);
  }
  float3 rgb = prt_channels(a0, a1, a2);
  float tail[3] = {0.0f, 0.0f, 0.0f};
  for (int c = PRT_CH12; c < PRT_CH; ++c)
    tail[c % 3] += prt_interp_one(btf, offsets, weights, n, c) * PRT_LSTAR1;
  rgb += (float3)(tail[0], tail[1], tail[2]);
  vstore3(rgb, i, image);
}

__kernel PRT_WG_ATTR void btf_view_cache(const uint slots, __global const int2* restrict slot_ids,
                                         __global const float4* restrict slot_geom,
                                         __global const float4* restrict slot_view,
                                         __global const float* restrict btf,
                                         __global const ulong* restrict part_offset,
                                         __global const int4* restrict part_info,
                                         __global float* restrict cache) {
  const uint s = get_global_id(0);
  PRT_GUARD(s, slots);
  const int2 ids = slot_ids[s];
  ulong offsets[PRT_PAIRS];
  float weights[PRT_PAIRS];
  const int n = prt_btf_pairs(part_offset[ids.y], part_info[ids.y], slot_geom[s].zw,
                              slot_view[s].xyz, offsets, weights);
  __global float* out = cache + (ulong)s * PRT_CH;
  for (int c = 0; c < PRT_CH12; c += 12) {
    float4 b0, b1, b2;
    prt_interp_chunk(btf, offsets, weights, n, c, &b0, &b1, &b2);
    vstore4(b0, 0, out + c);
    vstore4(b1, 1, out + c);
    vstore4(b2, 2, out + c);
  }
  for (int c = PRT_CH12; c < PRT_CH; ++c) out[c] = prt_interp_one(btf, offsets, weights, n, c);
}

__kernel PRT_WG_ATTR void btf_shade_cached(
    const uint pixels, __global const int* restrict code, __global const int2* restrict slot_ids,
    __global const float4* restrict slot_geom, __global const uint* restrict indices,
    __global const float* restrict radiance, __global const float* restrict cache,
    __global const float* restrict background, __global float* restrict image) {
  const uint i = get_global_id(0);
  PRT_GUARD(i, pixels);
  const int s = code[i];
  if (s < 0) {
    vstore3(vload3((uint)(-(s + 1)), background), i, image);
    return;
  }
  const float4 geom = slot_geom[s];
  const uint3 v = vload3((uint)slot_ids[s].x, indices);
  __global const float* l0 = radiance + (ulong)v.x * PRT_CH;
  __global const float* l1 = radiance + (ulong)v.y * PRT_CH;
  __global const float* l2 = radiance + (ulong)v.z * PRT_CH;
  const float w1 = geom.x, w2 = geom.y, w0 = 1.0f - w1 - w2;
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
  vstore3(rgb, i, image);
}
