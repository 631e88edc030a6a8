// A material backend in a plugin (tests/plugin/CMakeLists.txt builds it as a module against
// prtlab_core, loads it in plugin_load_test and runs the material conformance suite on it as
// ctest's plugin.material_conformance): the whole material interface, registered with the line a
// built-in material uses.
//
// Material `u8_vectors`: every (texel, view) vector b(texel, view, .) of 3 M floats is stored as
// u8 codes times one f32 step per vector, step = max / 255 (0 for an all-zero vector), code =
// round(value / step). Each value is off by at most step / 2, so
//   ||b~ - b||_2 <= sqrt(sum over vectors of 3 M (step / 2)^2),
// which compress() computes, divides by ||b||_2 and declares.
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/opencl/cl_runtime.h"
#include "prtlab/storage/archive.h"

namespace u8_vectors {

constexpr const char* kName = "u8_vectors";
constexpr int kStateVersion = 1;

// The material contract (compress/material_compressor.h); kernels/btf_lookup.cl comes before.
constexpr const char* kSource = R"CL(
#define PRT_MATERIAL_PARAMS , __global const uchar* restrict u8_codes, \
    __global const float* restrict u8_steps, __global const ulong* restrict u8_part_vector, \
    __global const int2* restrict u8_part_info
#define PRT_MATERIAL_ARGS , u8_codes, u8_steps, u8_part_vector, u8_part_info

typedef struct {
  ulong vector[PRT_TEXELS * 4];  // (texel, view) vector indices
  float weight[PRT_TEXELS * 4];  // interpolation weight times the vector's step
  int n;
} prt_material;

void prt_material_begin(prt_material* m, int part, float2 uv, float3 view PRT_MATERIAL_PARAMS) {
  const int2 info = u8_part_info[part];  // (U, view_side)
  int texels[4], views[4];
  float tw[4], vw[4];
  const int nt = prt_texel_samples(info.x, uv, texels, tw);
  prt_view_samples(info.y, view, views, vw);
  int n = 0;
  for (int t = 0; t < nt; ++t)
    for (int k = 0; k < 4; ++k) {
      const float w = tw[t] * vw[k];
      if (w == 0.0f) continue;
      const ulong v = u8_part_vector[part] + (ulong)texels[t] * (ulong)(info.y * info.y) +
                      (ulong)views[k];
      m->vector[n] = v;
      m->weight[n] = w * u8_steps[v];
      ++n;
    }
  m->n = n;
}

void prt_material_chunk(const prt_material* m, int c, float4* b0, float4* b1,
                        float4* b2 PRT_MATERIAL_PARAMS) {
  float4 s0 = (float4)(0.0f), s1 = (float4)(0.0f), s2 = (float4)(0.0f);
  for (int p = 0; p < m->n; ++p) {
    __global const uchar* q = u8_codes + m->vector[p] * (ulong)PRT_CH + c;
    const float w = m->weight[p];
    s0 += w * convert_float4(vload4(0, q));
    s1 += w * convert_float4(vload4(1, q));
    s2 += w * convert_float4(vload4(2, q));
  }
  *b0 = s0;
  *b1 = s1;
  *b2 = s2;
}

float prt_material_one(const prt_material* m, int c PRT_MATERIAL_PARAMS) {
  float s = 0.0f;
  for (int p = 0; p < m->n; ++p)
    s += m->weight[p] * (float)u8_codes[m->vector[p] * (ulong)PRT_CH + c];
  return s;
}
)CL";

class Material;

class Device final : public prt::DeviceMaterial {
 public:
  Device(prt::ClContext& ctx, std::span<const Material* const> parts);
  std::string label() const override { return "u8_vectors.cl"; }
  std::string source() const override { return kSource; }
  void set_args(cl::Kernel& k, unsigned first) const override {
    prt::set_args_from(k, first, codes_, steps_, part_vector_, part_info_);
  }
  std::uint64_t device_bytes() const override { return bytes_; }
  std::uint64_t bytes_per_hit(std::size_t, prt::TexelFilter filter) const override {
    const std::uint64_t texels = filter == prt::TexelFilter::kBilinear ? 4 : 1;
    return texels * 4 * (3 * static_cast<std::uint64_t>(m_) + 4);
  }

 private:
  cl::Buffer codes_, steps_, part_vector_, part_info_;
  int m_ = 0;
  std::uint64_t bytes_ = 0;
};

class Material final : public prt::CompressedMaterial {
 public:
  Material(prt::MaterialSampling s, std::vector<std::uint8_t> codes, std::vector<float> steps,
           double bound)
      : s_(std::move(s)), codes_(std::move(codes)), steps_(std::move(steps)), bound_(bound) {}

  static std::unique_ptr<prt::CompressedMaterial> compress(const prt::Btf& btf) {
    const prt::MaterialSampling s = prt::sampling_of(btf);
    const std::size_t vectors = static_cast<std::size_t>(s.texel_count()) * s.view_count();
    const std::size_t ch = 3 * static_cast<std::size_t>(s.light_count());
    std::vector<std::uint8_t> codes(vectors * ch);
    std::vector<float> steps(vectors);
    tbb::parallel_for(std::size_t{0}, vectors, [&](std::size_t v) {
      const float* b = btf.data().data() + v * ch;
      const float peak = *std::max_element(b, b + ch);
      const float step = peak > 0.0f ? peak / 255.0f : 0.0f;
      steps[v] = step;
      for (std::size_t c = 0; c < ch; ++c)
        codes[v * ch + c] =
            step > 0.0f ? static_cast<std::uint8_t>(std::lround(std::max(b[c], 0.0f) / step)) : 0;
    });
    double err2 = 0, ref2 = 0;
    for (float step : steps) err2 += static_cast<double>(ch) * 0.25 * step * step;
    for (float x : btf.data()) ref2 += static_cast<double>(x) * x;
    const double bound = ref2 > 0 ? std::sqrt(err2 / ref2) : 0.0;
    return std::make_unique<Material>(s, std::move(codes), std::move(steps), bound);
  }

  static std::unique_ptr<prt::CompressedMaterial> load(const prt::ArchiveReader& r) {
    const auto meta = r.meta_value<nlohmann::json>(kName);
    try {
      if (meta.at("format_version").get<int>() != kStateVersion)
        throw prt::InputError(r.path(), "u8_vectors: unknown state version");
      prt::MaterialSampling s{meta.at("material").get<std::string>(),
                              meta.at("resolution").get<int>(), meta.at("view_side").get<int>(),
                              meta.at("light_side").get<int>()};
      if (s.resolution < 1 || s.view_side < 1 || s.light_side < 1 || s.resolution > 4096 ||
          s.view_side > 64 || s.light_side > 64)
        throw prt::InputError(r.path(), "u8_vectors: sampling out of range");
      const std::uint64_t vectors = static_cast<std::uint64_t>(s.texel_count()) * s.view_count();
      return std::make_unique<Material>(
          s, r.section<std::uint8_t>("codes", vectors * 3 * s.light_count()),
          r.section<float>("steps", vectors), meta.at("bound").get<double>());
    } catch (const nlohmann::json::exception& e) {
      throw prt::InputError(r.path(), fmt::format("u8_vectors: bad metadata ({})", e.what()));
    }
  }

  std::string backend() const override { return kName; }
  prt::StorageReport storage() const override {
    return {{{"codes", codes_.size(), "u8 per value, codes[(texel * V + view) * 3M + 3 j + c]"},
             {"steps", steps_.size() * 4, "f32 step per (texel, view) vector"}}};
  }
  double flops_per_pixel() const override {
    return 2.0 * 4 * s_.light_count() + 2.0 * s_.light_count();
  }
  double declared_error_bound() const override { return bound_; }
  prt::MaterialLightBasis light_basis() const override {
    return prt::MaterialLightBasis::pixel_bins(s_.light_side);
  }
  prt::MaterialSampling sampling() const override { return s_; }
  prt::Rgb reflectance(int texel, int view, int light) const override {
    const std::size_t v = static_cast<std::size_t>(texel) * s_.view_count() + view;
    const std::uint8_t* c = codes_.data() + v * 3 * s_.light_count() + 3 * light;
    return prt::Rgb(c[0], c[1], c[2]) * steps_[v];
  }
  void eval_lights(prt::Vec2 uv, prt::Vec3 e, std::span<prt::Rgb> out,
                   prt::TexelFilter filter) const override {
    // The kernel's order: texel outer, view inner, step folded into the weight.
    const prt::BtfViewSamples vs = prt::btf_view_samples(s_.view_side, e);
    const prt::BtfTexelSamples ts = prt::btf_texel_samples(s_.resolution, uv, filter);
    std::fill(out.begin(), out.end(), prt::Rgb(0.0f));
    for (int t = 0; t < ts.count; ++t)
      for (int k = 0; k < 4; ++k) {
        const float w = ts.weight[t] * vs.weight[k];
        if (w == 0.0f) continue;
        const std::size_t v = static_cast<std::size_t>(ts.texel[t]) * s_.view_count() + vs.view[k];
        const float ws = w * steps_[v];
        const std::uint8_t* c = codes_.data() + v * 3 * s_.light_count();
        for (int j = 0; j < s_.light_count(); ++j)
          out[j] += ws * prt::Rgb(c[3 * j], c[3 * j + 1], c[3 * j + 2]);
      }
  }
  std::unique_ptr<prt::DeviceMaterial> upload(prt::ClContext& ctx,
                                              std::span<const prt::CompressedMaterial* const> parts,
                                              const prt::ParamSet&) const override {
    std::vector<const Material*> mine;
    for (const auto* p : parts) {
      const auto* m = dynamic_cast<const Material*>(p);
      if (!m) throw prt::ParameterError("u8_vectors: a part's material is of another backend");
      mine.push_back(m);
    }
    return std::make_unique<Device>(ctx, mine);
  }
  void save(prt::ArchiveWriter& w) const override {
    w.add_meta(kName, {{"format_version", kStateVersion},
                       {"material", s_.material},
                       {"resolution", s_.resolution},
                       {"view_side", s_.view_side},
                       {"light_side", s_.light_side},
                       {"bound", bound_}});
    w.add_section("codes", codes_);
    w.add_section("steps", steps_);
  }

  const prt::MaterialSampling& s() const { return s_; }
  const std::vector<std::uint8_t>& codes() const { return codes_; }
  const std::vector<float>& steps() const { return steps_; }

 private:
  prt::MaterialSampling s_;
  std::vector<std::uint8_t> codes_;
  std::vector<float> steps_;
  double bound_ = 0;
};

Device::Device(prt::ClContext& ctx, std::span<const Material* const> parts) {
  std::vector<std::uint8_t> codes;
  std::vector<float> steps;
  std::vector<cl_ulong> part_vector;
  std::vector<cl_int2> info;
  for (const Material* p : parts) {
    part_vector.push_back(steps.size());
    info.push_back(cl_int2{{p->s().resolution, p->s().view_side}});
    codes.insert(codes.end(), p->codes().begin(), p->codes().end());
    steps.insert(steps.end(), p->steps().begin(), p->steps().end());
  }
  m_ = parts.front()->s().light_count();
  codes_ = prt::upload(ctx, std::span<const std::uint8_t>(codes), "u8_vectors codes");
  steps_ = prt::upload(ctx, std::span<const float>(steps), "u8_vectors steps");
  part_vector_ = prt::upload(ctx, std::span<const cl_ulong>(part_vector), "u8_vectors parts");
  part_info_ = prt::upload(ctx, std::span<const cl_int2>(info), "u8_vectors parts");
  bytes_ = codes.size() + steps.size() * 4 + part_vector.size() * 8 + info.size() * 8;
}

class Compressor final : public prt::MaterialCompressor {
 public:
  std::unique_ptr<prt::CompressedMaterial> compress(const prt::MaterialInput& input,
                                                    prt::Progress& progress) const override {
    if (!input.btf) throw prt::ParameterError("u8_vectors: no BTF given");
    auto out = Material::compress(*input.btf);
    progress.finish();
    return out;
  }
};

prt::MaterialEntry entry() {
  prt::MaterialEntry e;
  e.name = kName;
  e.description = "test plugin: each (texel, view) vector as u8 codes x one f32 step";
  e.create = [](const prt::ParamSet&) { return std::make_unique<Compressor>(); };
  e.load = &Material::load;
  return e;
}

PRT_REGISTER_MATERIAL(entry);

}  // namespace u8_vectors
