// Material `svd` (compressors/svd/svd_material.h): the material contract of
// compress/material_compressor.h over a rank-K truncation of each ABRDF (SVD_PCA 0) or a PCA of
// the texels (SVD_PCA 1), with the arrays and the order of operations of SvdMaterial::eval_lights.
// kernels/btf_lookup.cl comes before this file.
//
// Host defines: SVD_PCA (0 abrdf, 1 texel_pca), SVD_RANK (the largest K of the parts: the size
// of the private arrays).
//
// Data (float offsets into svd_a and svd_b from each part's bases):
//   abrdf      svd_a  view factors  [((texel V + view) K + r) 3 + channel]
//              svd_b  light factors [((texel K + r) M + light) 3 + channel]
//   texel_pca  svd_a  coefficients  [texel K + r]
//              svd_b  the mean then the K components: [(r V + view) 3M + 3 light + channel],
//                     r = 0 the mean (coefficient 1), r = 1 .. K the components
//   svd_part_info  per part (U, view_side, K, 0)
//   svd_part_base  per part (first float in svd_a, first float in svd_b)

#ifndef SVD_PCA
#define SVD_PCA 0
#endif
#ifndef SVD_RANK
#define SVD_RANK 1
#endif

#define PRT_MATERIAL_PARAMS                                                                    \
  , __global const float *restrict svd_a, __global const float *restrict svd_b,               \
      __global const int4 *restrict svd_part_info, __global const ulong2 *restrict svd_part_base
#define PRT_MATERIAL_ARGS , svd_a, svd_b, svd_part_info, svd_part_base

#if SVD_PCA

typedef struct {
  ulong view_base[4];  // in svd_b: the part's basis + view * 3M
  float view_w[4];
  ulong stride;  // floats of one basis vector: V 3M
  int k;
  float a[SVD_RANK + 1];  // 1, then the texels' mixed coefficients
} prt_material;

void prt_material_begin(prt_material* m, int part, float2 uv, float3 view PRT_MATERIAL_PARAMS) {
  const int4 info = svd_part_info[part];
  const ulong2 base = svd_part_base[part];
  const int res = info.x, side = info.y, k = info.z;
  int texels[4];
  float texel_w[4];
  const int count = prt_texel_samples(res, uv, texels, texel_w);
  m->k = k;
  m->a[0] = 1.0f;
  for (int r = 0; r < k; ++r) m->a[r + 1] = 0.0f;
  for (int t = 0; t < count; ++t) {
    __global const float* c = svd_a + base.x + (ulong)texels[t] * (ulong)k;
    for (int r = 0; r < k; ++r) m->a[r + 1] += texel_w[t] * c[r];
  }
  int views[4];
  prt_view_samples(side, view, views, m->view_w);
  for (int q = 0; q < 4; ++q) m->view_base[q] = base.y + (ulong)views[q] * (ulong)PRT_CH;
  m->stride = (ulong)(side * side) * (ulong)PRT_CH;
}

void prt_material_chunk(const prt_material* m, int c, float4* b0, float4* b1,
                        float4* b2 PRT_MATERIAL_PARAMS) {
  float4 s0 = (float4)(0.0f), s1 = (float4)(0.0f), s2 = (float4)(0.0f);
  for (int q = 0; q < 4; ++q) {
    const float w = m->view_w[q];
    if (w == 0.0f) continue;
    float4 t0 = (float4)(0.0f), t1 = (float4)(0.0f), t2 = (float4)(0.0f);
    for (int r = 0; r <= m->k; ++r) {
      __global const float* p = svd_b + m->view_base[q] + (ulong)r * m->stride + (ulong)c;
      const float a = m->a[r];
      t0 += a * vload4(0, p);
      t1 += a * vload4(1, p);
      t2 += a * vload4(2, p);
    }
    s0 += w * t0;
    s1 += w * t1;
    s2 += w * t2;
  }
  *b0 = s0;
  *b1 = s1;
  *b2 = s2;
}

float prt_material_one(const prt_material* m, int c PRT_MATERIAL_PARAMS) {
  float s = 0.0f;
  for (int q = 0; q < 4; ++q) {
    const float w = m->view_w[q];
    if (w == 0.0f) continue;
    float t = 0.0f;
    for (int r = 0; r <= m->k; ++r)
      t += m->a[r] * svd_b[m->view_base[q] + (ulong)r * m->stride + (ulong)c];
    s += w * t;
  }
  return s;
}

#else  // abrdf

typedef struct {
  ulong light_base[PRT_TEXELS];  // in svd_b: the texel's light factors
  float3 a[PRT_TEXELS * SVD_RANK];  // texel weight x the view factors at the view, per r
  int n, k;
} prt_material;

void prt_material_begin(prt_material* m, int part, float2 uv, float3 view PRT_MATERIAL_PARAMS) {
  const int4 info = svd_part_info[part];
  const ulong2 base = svd_part_base[part];
  const int res = info.x, side = info.y, k = info.z;
  int texels[4];
  float texel_w[4];
  const int count = prt_texel_samples(res, uv, texels, texel_w);
  int views[4];
  float view_w[4];
  prt_view_samples(side, view, views, view_w);
  const ulong view_floats = (ulong)(side * side) * (ulong)k * 3;
  for (int t = 0; t < count; ++t) {
    __global const float* u = svd_a + base.x + (ulong)texels[t] * view_floats;
    for (int r = 0; r < k; ++r) {
      float3 sum = (float3)(0.0f);
      for (int q = 0; q < 4; ++q) sum += view_w[q] * vload3(views[q] * k + r, u);
      m->a[t * SVD_RANK + r] = texel_w[t] * sum;
    }
    m->light_base[t] = base.y + (ulong)texels[t] * (ulong)k * (ulong)PRT_CH;
  }
  m->n = count;
  m->k = k;
}

void prt_material_chunk(const prt_material* m, int c, float4* b0, float4* b1,
                        float4* b2 PRT_MATERIAL_PARAMS) {
  // Floats c .. c + 11 are the channels (0 1 2 0) (1 2 0 1) (2 0 1 2): c is a multiple of 12.
  float4 s0 = (float4)(0.0f), s1 = (float4)(0.0f), s2 = (float4)(0.0f);
  for (int t = 0; t < m->n; ++t) {
    for (int r = 0; r < m->k; ++r) {
      const float3 a = m->a[t * SVD_RANK + r];
      __global const float* p = svd_b + m->light_base[t] + (ulong)r * (ulong)PRT_CH + (ulong)c;
      s0 += (float4)(a.x, a.y, a.z, a.x) * vload4(0, p);
      s1 += (float4)(a.y, a.z, a.x, a.y) * vload4(1, p);
      s2 += (float4)(a.z, a.x, a.y, a.z) * vload4(2, p);
    }
  }
  *b0 = s0;
  *b1 = s1;
  *b2 = s2;
}

float prt_material_one(const prt_material* m, int c PRT_MATERIAL_PARAMS) {
  const int ch = c % 3;
  float s = 0.0f;
  for (int t = 0; t < m->n; ++t)
    for (int r = 0; r < m->k; ++r) {
      const float3 a = m->a[t * SVD_RANK + r];
      const float ac = ch == 0 ? a.x : (ch == 1 ? a.y : a.z);
      s += ac * svd_b[m->light_base[t] + (ulong)r * (ulong)PRT_CH + (ulong)c];
    }
  return s;
}

#endif
