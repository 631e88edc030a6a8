// Material `packed` (compressors/packed/packed.h): the material contract of
// compress/material_compressor.h over float16 or 8-bit codes. kernels/btf_lookup.cl comes before
// this file. Host define PACKED_U8 (1: 8-bit codes with a scale per vector; 0: float16).
//
// Data:
//   packed_codes      every distinct part's vectors, codes[vector * 3M + 3 j + c] (half or uchar)
//   packed_scales     per vector (u8 only): v = scale * code
//   packed_slots      per part texel, its storage slot (tiled order), from the part's slot base
//   packed_part_base  per part, the index of its first vector
//   packed_part_info  per part (U, view_side, view_independent, slot base)
// Vector of (texel, view): part_base + slot(texel) * V' + view (V' = 1 and view 0 for a
// view-independent part, else V = view_side^2).

#ifndef PACKED_U8
#define PACKED_U8 1
#endif

#if PACKED_U8
#define PACKED_T uchar
#define PACKED_LOAD4(k, p) convert_float4(vload4((k), (p)))
#define PACKED_LOAD1(p) convert_float(*(p))
#else
#define PACKED_T half
#define PACKED_LOAD4(k, p) vload_half4((k), (p))
#define PACKED_LOAD1(p) vload_half(0, (p))
#endif

#define PRT_MATERIAL_PARAMS                                                                       \
  , __global const PACKED_T *restrict packed_codes, __global const float *restrict packed_scales, \
      __global const int *restrict packed_slots, __global const ulong *restrict packed_part_base, \
      __global const int4 *restrict packed_part_info
#define PRT_MATERIAL_ARGS \
  , packed_codes, packed_scales, packed_slots, packed_part_base, packed_part_info

#define PACKED_PAIRS (PRT_TEXELS * 4)

typedef struct {
  uint offsets[PACKED_PAIRS];  // of the pairs' vectors, in values
  float weights[PACKED_PAIRS];  // u8: the pair's weight times its vector's scale
  int n;
} prt_material;

#define PRT_MATERIAL_SLOT_VIEWS 1

// The pairs of the texels around uv and the given view samples (texel outer, view inner, zero
// weights dropped).
void packed_pairs(prt_material* m, int part, float2 uv, const int* views, const float* view_w,
                  int view_count PRT_MATERIAL_PARAMS) {
  const int4 info = packed_part_info[part];
  const ulong base = packed_part_base[part];
  const int side = info.y;
  int texels[4];
  float texel_w[4];
  const int texel_count = prt_texel_samples(info.x, uv, texels, texel_w);
  const uint vcount = info.z ? 1u : (uint)(side * side);
  int n = 0;
  for (int t = 0; t < texel_count; ++t) {
    const uint slot = (uint)packed_slots[info.w + texels[t]];
    for (int k = 0; k < view_count; ++k) {
      const float w = texel_w[t] * view_w[k];
      if (w == 0.0f) continue;
      const uint vec = (uint)base + slot * vcount + (uint)views[k];
      m->offsets[n] = vec * (uint)PRT_CH;
#if PACKED_U8
      m->weights[n] = w * packed_scales[vec];
#else
      m->weights[n] = w;
#endif
      ++n;
    }
  }
  m->n = n;
}

void prt_material_begin(prt_material* m, int part, float2 uv, float3 view PRT_MATERIAL_PARAMS) {
  const int4 info = packed_part_info[part];
  int views[4];
  float view_w[4];
  const int count = prt_part_view_samples(info.y, info.z, view, views, view_w);
  packed_pairs(m, part, uv, views, view_w, count PRT_MATERIAL_ARGS);
}

void prt_material_begin_views(prt_material* m, int part, float2 uv, int4 views4,
                              float4 weights4 PRT_MATERIAL_PARAMS) {
  int views[4];
  float view_w[4];
  const int count =
      prt_given_view_samples(views4, weights4, packed_part_info[part].z, views, view_w);
  packed_pairs(m, part, uv, views, view_w, count PRT_MATERIAL_ARGS);
}

void prt_material_chunk(const prt_material* m, int c, float4* b0, float4* b1,
                        float4* b2 PRT_MATERIAL_PARAMS) {
  float4 s0 = (float4)(0.0f), s1 = (float4)(0.0f), s2 = (float4)(0.0f);
  for (int p = 0; p < m->n; ++p) {
    __global const PACKED_T* q = packed_codes + m->offsets[p] + c;
    const float w = m->weights[p];
    s0 += w * PACKED_LOAD4(0, q);
    s1 += w * PACKED_LOAD4(1, q);
    s2 += w * PACKED_LOAD4(2, q);
  }
  *b0 = s0;
  *b1 = s1;
  *b2 = s2;
}

float prt_material_one(const prt_material* m, int c PRT_MATERIAL_PARAMS) {
  float s = 0.0f;
  for (int p = 0; p < m->n; ++p) s += m->weights[p] * PACKED_LOAD1(packed_codes + m->offsets[p] + c);
  return s;
}
