// The head of every BTF shading program (core/src/render/shading_program.cpp): the defines the
// host sets, and the lookups of btf.h in float (the view interpolation on the sphere, texel
// lookup with wrap-around) for any material's source (compress/material_compressor.h, "the
// material contract"), which follows this file; kernels/btf_shading.cl comes last.
//
// Host defines: PRT_M (values of the light basis: M light bins, or SH coefficients),
// PRT_BILINEAR (0 nearest, 1 bilinear texels), PRT_WG_SIZE.

#ifndef PRT_M
#define PRT_M 64
#endif
#ifndef PRT_BILINEAR
#define PRT_BILINEAR 0
#endif
// Floats of one reflectance vector b(u, e, .) (packed RGB), and the part done 12 at a time.
#define PRT_CH (3 * PRT_M)
#define PRT_CH12 (PRT_CH - PRT_CH % 12)
// Texels a lookup reads: 1 nearest, 4 bilinear.
#if PRT_BILINEAR
#define PRT_TEXELS 4
#else
#define PRT_TEXELS 1
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
#ifdef PRT_PROBE_FIXED_VIEWS
  // A benchmark's probe (render/btf_shading.h, ShadingProbe): 4 neighbouring views chosen by
  // the view's x alone, in place of the sphere's interpolation.
  const int v0 = ((int)(fabs(view.x) * (float)(side - 1))) * side + side / 2 - 1;
  views[0] = clamp(v0, 0, side * side - 1);
  views[1] = clamp(v0 + 1, 0, side * side - 1);
  views[2] = clamp(v0 + side, 0, side * side - 1);
  views[3] = clamp(v0 + side + 1, 0, side * side - 1);
  weights[0] = weights[1] = weights[2] = weights[3] = 0.25f;
  return;
#endif
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

// The view samples of a lookup on a part's grid of `side`: the 4 around `view`, or view 0 with
// weight 1 for a view-independent part. Returns how many (4 or 1).
int prt_part_view_samples(int side, int view_independent, float3 view, int* views, float* w) {
  views[0] = views[1] = views[2] = views[3] = 0;
  w[0] = 1.0f;
  w[1] = w[2] = w[3] = 0.0f;
  if (view_independent) return 1;
  prt_view_samples(side, view, views, w);
  return 4;
}

// The same from samples computed beforehand (btf_slot_view_samples).
int prt_given_view_samples(int4 given, float4 given_w, int view_independent, int* views,
                           float* w) {
  views[0] = given.x, views[1] = given.y, views[2] = given.z, views[3] = given.w;
  w[0] = given_w.x, w[1] = given_w.y, w[2] = given_w.z, w[3] = given_w.w;
  if (!view_independent) return 4;
  views[0] = 0;
  w[0] = 1.0f;
  return 1;
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

// Btf::texel_samples: the 1 (nearest) or 4 (bilinear) texels of a U x U tile at uv, wrapping,
// and their weights, in the order of prt_bilinear_corners. Returns how many.
int prt_texel_samples(int res, float2 uv, int* texels, float* weights) {
#if PRT_BILINEAR
  const float fx = prt_fract(uv.x) * (float)res - 0.5f, fy = prt_fract(uv.y) * (float)res - 0.5f;
  const float x0f = floor(fx), y0f = floor(fy);
  const float tx = fx - x0f, ty = fy - y0f;
  const int x0 = prt_wrap((int)x0f, res), x1 = prt_wrap(x0 + 1, res);
  const int y0 = prt_wrap((int)y0f, res), y1 = prt_wrap(y0 + 1, res);
  prt_bilinear_corners(x0, x1, y0, y1, res, tx, ty, texels, weights);
  return 4;
#else
  const int x = min((int)(prt_fract(uv.x) * (float)res), res - 1);
  const int y = min((int)(prt_fract(uv.y) * (float)res), res - 1);
  texels[0] = y * res + x;
  weights[0] = 1.0f;
  return 1;
#endif
}

// ---- prt_view_samples for 16 view directions at once --------------------------------------
// The same arithmetic as the scalar functions above, lane by lane, with selects for their
// branches: PoCL runs a work-item's scalar code one pixel at a time (it vectorises nothing
// across work-items in the shading kernels), so 16 pixels a work-item in float16 is what puts
// the view samples on the vector units.

float16 prt_atan_unit16(float16 z) {
  const float16 az = fabs(z);
  const int16 big = az > 0.41421356237f;
  const float16 x = select(az, (az - 1.0f) / (az + 1.0f), big);
  const float16 x2 = x * x;
  const float16 p = (((8.05374449538e-2f * x2 - 1.38776856032e-1f) * x2 + 1.99777106478e-1f) * x2 -
                     3.33329491539e-1f) *
                        x2 * x +
                    x;
  return copysign(select((float16)(0.0f), (float16)(PRT_QUARTER_PI_F), big) + p, z);
}

void prt_sincos_quarter16(float16 t, float16* s_out, float16* c_out) {
  const float16 t2 = t * t;
  *s_out =
      t *
      (1.0f -
       t2 / 6.0f *
           (1.0f - t2 / 20.0f * (1.0f - t2 / 42.0f * (1.0f - t2 / 72.0f * (1.0f - t2 / 110.0f)))));
  *c_out =
      1.0f -
      t2 / 2.0f *
          (1.0f - t2 / 12.0f * (1.0f - t2 / 30.0f * (1.0f - t2 / 56.0f * (1.0f - t2 / 90.0f))));
}

void prt_square_to_hemisphere16(float16 a, float16 b, float16* ox, float16* oy, float16* oz) {
  const float16 u = 2.0f * a - 1.0f, v = 2.0f * b - 1.0f;
  const int16 centre = u == 0.0f && v == 0.0f;
  const int16 horizontal = fabs(u) > fabs(v);
  const float16 r = select(v, u, horizontal);
  float16 s, c;
  prt_sincos_quarter16(PRT_QUARTER_PI_F * select(u / v, v / u, horizontal), &s, &c);
  const float16 cos_phi = select(s, c, horizontal), sin_phi = select(c, s, horizontal);
  const float16 r2 = fmin(r * r, 1.0f);
  const float16 f = sqrt(2.0f - r2);
  *ox = select(r * cos_phi * f, (float16)(0.0f), centre);
  *oy = select(r * sin_phi * f, (float16)(0.0f), centre);
  *oz = select(1.0f - r2, (float16)(1.0f), centre);
}

void prt_view_samples16(int16 side, float16 vx, float16 vy, float16 vz, int16* views,
                        float16* weights) {
  // prt_clamp_to_hemisphere
  const int16 finite = isfinite(vx) && isfinite(vy) && isfinite(vz);
  const int16 axis = vx == 0.0f && vy == 0.0f;
  const float16 cz = fmax(vz, 0.0f);
  const float16 inv_len = 1.0f / sqrt(vx * vx + vy * vy + cz * cz);
  float16 ex = vx * inv_len, ey = vy * inv_len, ez = cz * inv_len;
  ex = select(ex, select((float16)(0.0f), (float16)(1.0f), vz < 0.0f), axis);
  ey = select(ey, (float16)(0.0f), axis);
  ez = select(ez, select((float16)(1.0f), (float16)(0.0f), vz < 0.0f), axis);
  ex = select((float16)(0.0f), ex, finite);
  ey = select((float16)(0.0f), ey, finite);
  ez = select((float16)(1.0f), ez, finite);
  // prt_hemisphere_to_square
  const float16 inv = 1.0f / sqrt(1.0f + fabs(ez));
  const float16 x = ex * inv, y = ey * inv;
  const float16 r = sqrt(x * x + y * y);
  const int16 wide = fabs(x) >= fabs(y);
  const float16 ru = select(select(-r, r, y > 0.0f), select(-r, r, x > 0.0f), wide);
  const float16 other = prt_atan_unit16(select(x / y, y / x, wide)) / PRT_QUARTER_PI_F * ru;
  const float16 u = select(other, ru, wide), v = select(ru, other, wide);
  const int16 origin = r == 0.0f;
  const float16 ax = select(0.5f * (u + 1.0f), (float16)(0.5f), origin);
  const float16 ay = select(0.5f * (v + 1.0f), (float16)(0.5f), origin);
  // the grid cells around (ax, ay) and the fractions measured on the sphere
  const float16 sidef = convert_float16(side);
  const int16 ix = convert_int16(floor(ax * sidef - 0.5f));
  const int16 iy = convert_int16(floor(ay * sidef - 0.5f));
  const int16 x0 = clamp(ix, (int16)(0), side - 1), x1 = clamp(ix + 1, (int16)(0), side - 1);
  const int16 y0 = clamp(iy, (int16)(0), side - 1), y1 = clamp(iy + 1, (int16)(0), side - 1);
  float16 px0, py0, pz0, px1, py1, pz1;
  prt_square_to_hemisphere16((convert_float16(x0) + 0.5f) / sidef, ay, &px0, &py0, &pz0);
  prt_square_to_hemisphere16((convert_float16(x1) + 0.5f) / sidef, ay, &px1, &py1, &pz1);
  float16 d0 = sqrt((ex - px0) * (ex - px0) + (ey - py0) * (ey - py0) + (ez - pz0) * (ez - pz0));
  float16 d1 = sqrt((ex - px1) * (ex - px1) + (ey - py1) * (ey - py1) + (ez - pz1) * (ez - pz1));
  const float16 tx =
      select((float16)(0.0f), select((float16)(0.0f), d0 / (d0 + d1), d0 + d1 > 0.0f), x0 != x1);
  prt_square_to_hemisphere16(ax, (convert_float16(y0) + 0.5f) / sidef, &px0, &py0, &pz0);
  prt_square_to_hemisphere16(ax, (convert_float16(y1) + 0.5f) / sidef, &px1, &py1, &pz1);
  d0 = sqrt((ex - px0) * (ex - px0) + (ey - py0) * (ey - py0) + (ez - pz0) * (ez - pz0));
  d1 = sqrt((ex - px1) * (ex - px1) + (ey - py1) * (ey - py1) + (ez - pz1) * (ez - pz1));
  const float16 ty =
      select((float16)(0.0f), select((float16)(0.0f), d0 / (d0 + d1), d0 + d1 > 0.0f), y0 != y1);
  views[0] = y0 * side + x0;
  views[1] = y0 * side + x1;
  views[2] = y1 * side + x0;
  views[3] = y1 * side + x1;
  weights[0] = (1.0f - tx) * (1.0f - ty);
  weights[1] = tx * (1.0f - ty);
  weights[2] = (1.0f - tx) * ty;
  weights[3] = tx * ty;
}
