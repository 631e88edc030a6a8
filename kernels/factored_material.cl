// A material stored as three factors per texel, f = Q(h) sum_k s_k P_k(d) R_k(e) per channel
// (render/factored_material.h: the `cmf` and `hf` materials of Suykens et al. 2003; one term
// but for cmf's multi-term fits). For a hit, prt_material_begin folds the light-independent part
// of each term of each texel sample, its filter weight x scale x R(e) (R read at the 4 view
// samples around e); each light then reads each term's P at its bin and the texel's Q at the 4
// halfway-grid samples around normalize(d_j + e), interpolated linearly or
// geometrically (exp of the interpolated log, a Q below FLT_MIN read as FLT_MIN) as the part's
// state says (render/factored_material.h). Implements the material
// contract of compress/material_compressor.h; kernels/btf_lookup.cl comes before this file.
//
// Data:
//   fm_books    every part's P, Q and R codebooks, packed float RGB
//   fm_texels   per texel and term of every part (a texel's terms consecutive): the float
//               offsets of the term's P, the texel's Q and the term's R entries in fm_books
//   fm_scales   per texel and term: the RGB scale
//   fm_info     per part: (U, view_side, half_side | geometric << 16 | terms << 20, first row
//               in fm_texels / fm_scales); geometric is 1 for the geometric halfway interpolation
//   fm_lights   the M light directions (xyz)
// FM_TERMS (the host's define) is the most terms of any part, the size of the private arrays.

#ifndef FM_TERMS
#define FM_TERMS 1
#endif

#define PRT_MATERIAL_PARAMS                                                             \
  , __global const float *restrict fm_books, __global const uint4 *restrict fm_texels,  \
      __global const float4 *restrict fm_scales, __global const int4 *restrict fm_info, \
      __global const float4 *restrict fm_lights
#define PRT_MATERIAL_ARGS , fm_books, fm_texels, fm_scales, fm_info, fm_lights

typedef struct {
  float3 e;
  int half_side;
  int geometric;
  int n;
  int terms;
  uint p[PRT_TEXELS * FM_TERMS];
  uint q[PRT_TEXELS];
  float3 coef[PRT_TEXELS * FM_TERMS];
} prt_material;

float3 fm_load3(__global const float* p) {
  return (float3)(p[0], p[1], p[2]);
}

void prt_material_begin(prt_material* m, int part, float2 uv, float3 view PRT_MATERIAL_PARAMS) {
  const int4 info = fm_info[part];
  const int res = info.x, side = info.y;
  m->e = prt_clamp_to_hemisphere(view);
  m->half_side = info.z & 0xffff;
  m->geometric = (info.z >> 16) & 1;
  const int stride = (info.z >> 20) & 0xf;
  const int terms = min(stride, FM_TERMS);
  m->terms = terms;
  int texels[4];
  float texel_w[4];
  const int count = prt_texel_samples(res, uv, texels, texel_w);
  int views[4];
  float view_w[4];
  prt_view_samples(side, m->e, views, view_w);
  for (int t = 0; t < count; ++t) {
    const int row = info.w + texels[t] * stride;
    for (int k = 0; k < terms; ++k) {
      const uint4 off = fm_texels[row + k];
      float3 re = (float3)(0.0f);
      for (int i = 0; i < 4; ++i) re += view_w[i] * fm_load3(fm_books + off.z + views[i] * 3);
      m->p[t * FM_TERMS + k] = off.x;
      if (k == 0) m->q[t] = off.y;
      m->coef[t * FM_TERMS + k] = (texel_w[t] * fm_scales[row + k].xyz) * re;
    }
  }
  m->n = count;
}

float3 fm_halfway(__global const float* q, const int* cells, const float* w, int geometric) {
  float3 v = (float3)(0.0f);
  if (!geometric) {
    for (int k = 0; k < 4; ++k) v += w[k] * fm_load3(q + cells[k] * 3);
    return v;
  }
  for (int k = 0; k < 4; ++k) v += w[k] * log(fmax(fm_load3(q + cells[k] * 3), (float3)(FLT_MIN)));
  return exp(v);
}

float3 fm_light(const prt_material* m, int j PRT_MATERIAL_PARAMS) {
  const float3 h = normalize(fm_lights[j].xyz + m->e);
  int cells[4];
  float w[4];
  prt_view_samples(m->half_side, h, cells, w);
  float3 sum = (float3)(0.0f);
  for (int t = 0; t < m->n; ++t) {
    const float3 qv = fm_halfway(fm_books + m->q[t], cells, w, m->geometric);
    for (int k = 0; k < m->terms; ++k)
      sum += m->coef[t * FM_TERMS + k] * fm_load3(fm_books + m->p[t * FM_TERMS + k] + j * 3) * qv;
  }
  return sum;
}

void prt_material_chunk(const prt_material* m, int c, float4* b0, float4* b1,
                        float4* b2 PRT_MATERIAL_PARAMS) {
  const int j = c / 3;
  const float3 v0 = fm_light(m, j PRT_MATERIAL_ARGS);
  const float3 v1 = fm_light(m, j + 1 PRT_MATERIAL_ARGS);
  const float3 v2 = fm_light(m, j + 2 PRT_MATERIAL_ARGS);
  const float3 v3 = fm_light(m, j + 3 PRT_MATERIAL_ARGS);
  *b0 = (float4)(v0.x, v0.y, v0.z, v1.x);
  *b1 = (float4)(v1.y, v1.z, v2.x, v2.y);
  *b2 = (float4)(v2.z, v3.x, v3.y, v3.z);
}

float prt_material_one(const prt_material* m, int c PRT_MATERIAL_PARAMS) {
  const float3 v = fm_light(m, c / 3 PRT_MATERIAL_ARGS);
  const int ch = c % 3;
  return ch == 0 ? v.x : (ch == 1 ? v.y : v.z);
}
