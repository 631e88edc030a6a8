// A material whose b(u, e, .) is a table of (texel, view) vectors (render/btf_table_material.h):
// the sampled BTF itself (material `full`, pixel light bins) or a radiance transfer texture (SH
// coefficients over the light direction). b(u, e, .) is the weighted sum of the table's
// vectors: 1 (nearest) or 4 (bilinear) texels x the 4 view samples around e
// (btf_view_samples), zero weights dropped. Implements the material
// contract of compress/material_compressor.h; kernels/btf_lookup.cl comes before this file.
//
// Data (packed float RGB, no padding; PRT_M values per vector):
//   table_values       every distinct part table, rgb[((texel * V + view) * M + j) * 3 + c]
//                      from the part's offset (floats); a view-independent table is stored with
//                      V = 1 (view 0 only)
//   table_part_offset  per part, the offset of its table in table_values
//   table_part_info    per part (U, view_side, view_independent, 0)

#define PRT_MATERIAL_PARAMS                                                         \
  , __global const float *restrict table_values, __global const ulong *restrict table_part_offset, \
      __global const int4 *restrict table_part_info
#define PRT_MATERIAL_ARGS , table_values, table_part_offset, table_part_info

#define TABLE_PAIRS (PRT_TEXELS * 4)

typedef struct {
  ulong offsets[TABLE_PAIRS];  // of the (texel, view) vectors, in floats
  float weights[TABLE_PAIRS];
  int n;
} prt_material;

#define PRT_MATERIAL_SLOT_VIEWS 1

// The pairs of the texels around uv and the given view samples (texel outer, view inner, zero
// weights dropped).
void prt_table_pairs(prt_material* m, int part, float2 uv, const int* views, const float* view_w,
                     int view_count PRT_MATERIAL_PARAMS) {
  const ulong base = table_part_offset[part];
  const int4 info = table_part_info[part];
  int texels[4];
  float texel_w[4];
  const int texel_count = prt_texel_samples(info.x, uv, texels, texel_w);
  const ulong vcount = info.z ? 1 : (ulong)info.y * (ulong)info.y;
  int n = 0;
  for (int t = 0; t < texel_count; ++t) {
    for (int k = 0; k < view_count; ++k) {
      const float w = texel_w[t] * view_w[k];
      if (w == 0.0f) continue;
      m->offsets[n] = base + ((ulong)texels[t] * vcount + (ulong)views[k]) * (ulong)PRT_CH;
      m->weights[n] = w;
      ++n;
    }
  }
  m->n = n;
}

// The (texel, view) vectors of a hit and their weights (Btf::texel_samples x btf_view_samples;
// a view-independent part, Btf::view_independent, has one vector per texel).
void prt_material_begin(prt_material* m, int part, float2 uv, float3 view PRT_MATERIAL_PARAMS) {
  const int4 info = table_part_info[part];
  int views[4];
  float view_w[4];
  const int count = prt_part_view_samples(info.y, info.z, view, views, view_w);
  prt_table_pairs(m, part, uv, views, view_w, count PRT_MATERIAL_ARGS);
}

void prt_material_begin_views(prt_material* m, int part, float2 uv, int4 views4,
                              float4 weights4 PRT_MATERIAL_PARAMS) {
  int views[4];
  float view_w[4];
  const int count =
      prt_given_view_samples(views4, weights4, table_part_info[part].z, views, view_w);
  prt_table_pairs(m, part, uv, views, view_w, count PRT_MATERIAL_ARGS);
}

void prt_material_chunk(const prt_material* m, int c, float4* b0, float4* b1,
                        float4* b2 PRT_MATERIAL_PARAMS) {
  float4 s0 = (float4)(0.0f), s1 = (float4)(0.0f), s2 = (float4)(0.0f);
  for (int p = 0; p < m->n; ++p) {
    __global const float* q = table_values + m->offsets[p] + c;
    const float w = m->weights[p];
    s0 += w * vload4(0, q);
    s1 += w * vload4(1, q);
    s2 += w * vload4(2, q);
  }
  *b0 = s0;
  *b1 = s1;
  *b2 = s2;
}

float prt_material_one(const prt_material* m, int c PRT_MATERIAL_PARAMS) {
  float s = 0.0f;
  for (int p = 0; p < m->n; ++p) s += m->weights[p] * table_values[m->offsets[p] + c];
  return s;
}
