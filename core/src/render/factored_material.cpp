#include "prtlab/render/factored_material.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>

#include "prtlab/base/error.h"
#include "prtlab/btf/halfway_parameterization.h"
#include "prtlab/compress/material_error.h"
#include "prtlab/numeric/kmeans.h"
#include "prtlab/numeric/quantization.h"
#include "prtlab/opencl/cl_runtime.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/storage/archive.h"
#include "prtlab/storage/index_section.h"

namespace prt {
namespace {

// Version 2 added "halfway_interpolation" (a version 1 state is linear), version 3 "terms" (an
// earlier state has one).
constexpr std::uint32_t kStateVersion = 3;
// Coordinate-descent sweeps of the K-term scale refit at most, and the relative change of the
// scales that ends it sooner.
constexpr int kScaleSweeps = 200;
constexpr double kScaleTolerance = 1e-12;
constexpr char kMetaKey[] = "factored";

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// One factor set (all texels' P, or Q, or R) after normalisation: texels x (n * 3).
struct FactorSet {
  int n = 0;  // directions per factor
  std::vector<float> values;
};

// Divides each texel's factor channel by its maximum (in place) and returns the maxima.
std::vector<float> normalise(std::vector<float>& v, int texels, int n) {
  std::vector<float> maxima(static_cast<std::size_t>(texels) * 3, 0.0f);
  for (int t = 0; t < texels; ++t)
    for (int c = 0; c < 3; ++c) {
      float* base = v.data() + static_cast<std::size_t>(t) * n * 3 + c;
      float mx = 0.0f;
      for (int i = 0; i < n; ++i) mx = std::max(mx, base[i * 3]);
      maxima[static_cast<std::size_t>(t) * 3 + c] = mx;
      const float inv = mx > 0.0f ? 1.0f / mx : 0.0f;
      for (int i = 0; i < n; ++i)
        base[i * 3] = mx > 0.0f ? std::min(base[i * 3] * inv, 1.0f) : 0.0f;
    }
  return maxima;
}

struct Codebook {
  int clusters = 0;
  std::vector<float> entries;  // clusters x n x 3
  std::vector<std::uint32_t> index;
};

Codebook cluster(const std::vector<float>& normalised, int texels, int n, const FactorCoding& c,
                 std::uint64_t seed_offset) {
  const std::size_t dims = static_cast<std::size_t>(n) * 3;
  Codebook out;
  if (c.clusters == 0) {
    out.clusters = texels;
    out.entries = normalised;
    out.index.resize(static_cast<std::size_t>(texels));
    for (int t = 0; t < texels; ++t)
      out.index[static_cast<std::size_t>(t)] = static_cast<std::uint32_t>(t);
    return out;
  }
  KMeansOptions o;
  o.clusters = std::min(c.clusters, texels);
  o.init = KMeansInit::kPlusPlus;
  o.seed = c.seed + seed_offset;
  o.max_iterations = c.kmeans_iterations;
  const KMeansResult r = kmeans(
      RowSet::dense(std::span<const float>(normalised), static_cast<std::size_t>(texels), dims), o);
  out.clusters = static_cast<int>(r.centroids.rows());
  out.entries.resize(static_cast<std::size_t>(out.clusters) * dims);
  for (int k = 0; k < out.clusters; ++k)
    for (std::size_t d = 0; d < dims; ++d)
      out.entries[static_cast<std::size_t>(k) * dims + d] =
          static_cast<float>(std::clamp(r.centroids(k, static_cast<Eigen::Index>(d)), 0.0, 1.0));
  out.index = r.assignments;
  return out;
}

// Decodes quantised blocks into floats (the only way decoded values are made, so that encode
// and load agree bit for bit).
// Codes are linear in x^(1 / gamma) (gamma 1: linear, the paper's textures).
std::vector<float> decode(const QuantizedBlocks& q, double gamma) {
  std::vector<float> out(q.rows * q.cols);
  for (std::size_t r = 0; r < q.rows; ++r)
    for (std::size_t c = 0; c < q.cols; ++c) {
      const double x = q.dequantize(r, c);
      out[r * q.cols + c] = static_cast<float>(gamma == 1.0 ? x : std::pow(x, gamma));
    }
  return out;
}

QuantizedBlocks blocks(std::size_t rows, std::size_t cols, std::vector<std::uint8_t> codes,
                       std::vector<float> scales) {
  QuantizedBlocks q;
  q.rows = rows;
  q.cols = cols;
  q.block_size = cols;
  q.range = QuantizationRange::kNonNegative;
  q.codes = std::move(codes);
  q.scales = std::move(scales);
  q.offsets.assign(q.scales.size(), 0.0f);
  return q;
}

void quantize_codebook(std::vector<float>& entries, int clusters, std::size_t dims, double gamma,
                       std::vector<std::uint8_t>& codes, std::vector<float>& scales) {
  std::vector<double> v(entries.begin(), entries.end());
  if (gamma != 1.0)
    for (double& x : v) x = std::pow(x, 1.0 / gamma);
  QuantizationOptions o;
  o.range = QuantizationRange::kNonNegative;
  QuantizedBlocks q = quantize_u8(v, static_cast<std::size_t>(clusters), dims, o);
  entries = decode(q, gamma);
  codes = std::move(q.codes);
  scales = std::move(q.scales);
}

// The scale map, 8 bits per channel over all texels with one global scale per channel (codes
// linear in s^(1 / gamma), as the codebooks').
void quantize_scale(std::vector<float>& scale, int texels, double gamma,
                    std::vector<std::uint8_t>& codes, std::vector<float>& global) {
  std::vector<double> planar(static_cast<std::size_t>(texels) * 3);
  for (int t = 0; t < texels; ++t)
    for (int c = 0; c < 3; ++c) {
      const double v = scale[static_cast<std::size_t>(t) * 3 + c];
      planar[static_cast<std::size_t>(c) * texels + t] =
          gamma == 1.0 ? v : std::pow(v, 1.0 / gamma);
    }
  QuantizationOptions o;
  o.range = QuantizationRange::kNonNegative;
  QuantizedBlocks q = quantize_u8(planar, 3, static_cast<std::size_t>(texels), o);
  const std::vector<float> d = decode(q, gamma);
  for (int t = 0; t < texels; ++t)
    for (int c = 0; c < 3; ++c)
      scale[static_cast<std::size_t>(t) * 3 + c] = d[static_cast<std::size_t>(c) * texels + t];
  codes = std::move(q.codes);
  global = std::move(q.scales);
}

std::vector<float> decode_scale(int texels, const std::vector<std::uint8_t>& codes,
                                const std::vector<float>& global, double gamma) {
  const std::vector<float> d =
      decode(blocks(3, static_cast<std::size_t>(texels), codes, global), gamma);
  std::vector<float> scale(static_cast<std::size_t>(texels) * 3);
  for (int t = 0; t < texels; ++t)
    for (int c = 0; c < 3; ++c)
      scale[static_cast<std::size_t>(t) * 3 + c] = d[static_cast<std::size_t>(c) * texels + t];
  return scale;
}

Rgb load3(const float* p) {
  return {p[0], p[1], p[2]};
}

// Q at a halfway direction from its 4 grid samples (the header's file comment; the kernel's
// fm_halfway).
Rgb interpolate_q(const float* q, const BtfViewSamples& h, HalfwayInterpolation mode) {
  Rgb v(0.0f);
  if (mode == HalfwayInterpolation::kLinear) {
    for (int k = 0; k < 4; ++k) v += h.weight[k] * load3(q + h.view[k] * 3);
    return v;
  }
  for (int k = 0; k < 4; ++k) {
    const float* a = q + h.view[k] * 3;
    for (int c = 0; c < 3; ++c) v[c] += h.weight[k] * std::log(std::max(a[c], FLT_MIN));
  }
  return {std::exp(v[0]), std::exp(v[1]), std::exp(v[2])};
}

}  // namespace

const char* halfway_interpolation_name(HalfwayInterpolation mode) {
  return mode == HalfwayInterpolation::kGeometric ? "geometric" : "linear";
}

AbrdfFactors::AbrdfFactors(int texel_count, int m, int h, int v, int term_count)
    : texels(texel_count),
      light_count(m),
      half_count(h),
      view_count(v),
      terms(term_count),
      p(static_cast<std::size_t>(texel_count) * term_count * m * 3),
      q(static_cast<std::size_t>(texel_count) * h * 3),
      r(static_cast<std::size_t>(texel_count) * term_count * v * 3) {}

FactoredMaterial::FactoredMaterial(State state) : state_(std::move(state)) {
  const MaterialSampling& s = state_.sampling;
  const auto texels = static_cast<std::size_t>(s.texel_count());
  const auto rows = texels * static_cast<std::size_t>(std::max(state_.terms, 0));
  PRT_CHECK(state_.half_side >= 1 && state_.terms >= 1 && state_.terms <= kMaxFactorTerms &&
                state_.index_p.size() == rows && state_.index_q.size() == texels &&
                state_.index_r.size() == rows && state_.scale.size() == rows * 3 &&
                state_.codebook_p.size() ==
                    static_cast<std::size_t>(state_.clusters_p) * s.light_count() * 3 &&
                state_.codebook_q.size() ==
                    static_cast<std::size_t>(state_.clusters_q) * half_count() * 3 &&
                state_.codebook_r.size() ==
                    static_cast<std::size_t>(state_.clusters_r) * s.view_count() * 3,
            "material {}: inconsistent factored state", state_.backend);
  lights_ = light_directions_f(s.light_side);
  for (const Vec3& e : light_directions_f(s.view_side)) views_.push_back(clamp_to_hemisphere(e));
}

const float* FactoredMaterial::p_entry(int texel, int term) const {
  return state_.codebook_p.data() +
         static_cast<std::size_t>(
             state_.index_p[static_cast<std::size_t>(texel) * state_.terms + term]) *
             state_.sampling.light_count() * 3;
}
const float* FactoredMaterial::q_entry(int texel) const {
  return state_.codebook_q.data() +
         static_cast<std::size_t>(state_.index_q[texel]) * half_count() * 3;
}
const float* FactoredMaterial::r_entry(int texel, int term) const {
  return state_.codebook_r.data() +
         static_cast<std::size_t>(
             state_.index_r[static_cast<std::size_t>(texel) * state_.terms + term]) *
             state_.sampling.view_count() * 3;
}
const float* FactoredMaterial::scale_of(int texel, int term) const {
  return state_.scale.data() + (static_cast<std::size_t>(texel) * state_.terms + term) * 3;
}

std::uint64_t FactoredMaterial::factored_bytes() const {
  const MaterialSampling& s = state_.sampling;
  const auto k = static_cast<std::uint64_t>(state_.terms);
  return static_cast<std::uint64_t>(s.texel_count()) *
         ((k * (s.light_count() + s.view_count()) + half_count()) * 3 + 3 * k) * sizeof(float);
}

StorageReport FactoredMaterial::storage() const {
  const MaterialSampling& s = state_.sampling;
  const std::uint64_t value = state_.quantized ? 1 : 4;
  const auto texels = static_cast<std::uint64_t>(s.texel_count());
  const auto book = [&](const char* name, int clusters, int n) {
    const std::uint64_t bytes = static_cast<std::uint64_t>(clusters) * n * 3 * value +
                                (state_.quantized ? static_cast<std::uint64_t>(clusters) * 4 : 0);
    return StorageComponent{
        name, bytes,
        fmt::format("{} entries x {} directions x RGB, {}", clusters, n,
                    state_.quantized ? "u8 with a float scale per entry" : "f32")};
  };
  const auto k = static_cast<std::uint64_t>(state_.terms);
  const std::uint64_t index =
      texels * (k * index_bytes(static_cast<std::uint64_t>(state_.clusters_p)) +
                index_bytes(static_cast<std::uint64_t>(state_.clusters_q)) +
                k * index_bytes(static_cast<std::uint64_t>(state_.clusters_r)));
  const std::string per = k == 1 ? "per texel" : fmt::format("per texel and term ({} terms)", k);
  return {{book("codebook_p", state_.clusters_p, s.light_count()),
           book("codebook_q", state_.clusters_q, half_count()),
           book("codebook_r", state_.clusters_r, s.view_count()),
           {"index_map", index,
            k == 1 ? "P, Q and R codebook indices per texel"
                   : fmt::format("P and R codebook indices {}, Q's per texel", per)},
           {"scale_map", texels * k * 3 * value + (state_.quantized ? 12 : 0),
            state_.quantized ? fmt::format("u8 RGB {}, one float scale per channel", per)
                             : fmt::format("f32 RGB {}", per)}}};
}

double FactoredMaterial::flops_per_pixel() const {
  // Per term R at the view (4 samples) times the scale, then per light the halfway lookup of Q
  // (4 samples), per term the product with P and its sum, and the dot product's multiply-add;
  // the halfway direction itself is a texture coordinate, shared by the channels, as in the
  // paper's vertex program. The geometric interpolation adds 4 logarithms and an exponential per
  // light, counted as one operation each (a GPU's special-function unit).
  const double m = state_.sampling.light_count();
  const double k = state_.terms;
  const double geometric = state_.interpolation == HalfwayInterpolation::kGeometric ? 5.0 : 0.0;
  return k * (8.0 + 2.0) + m * (8.0 + geometric + 2.0 * k + 2.0);
}

void FactoredMaterial::term_values(int texel, int view, int light, std::span<Rgb> out) const {
  PRT_CHECK(out.size() >= static_cast<std::size_t>(state_.terms),
            "material {}: {} values for {} terms", state_.backend, out.size(), state_.terms);
  const BtfViewSamples h = halfway_samples(state_.half_side, lights_[light], views_[view]);
  const Rgb qv = interpolate_q(q_entry(texel), h, state_.interpolation);
  for (int k = 0; k < state_.terms; ++k)
    out[static_cast<std::size_t>(k)] = load3(scale_of(texel, k)) *
                                       load3(p_entry(texel, k) + light * 3) * qv *
                                       load3(r_entry(texel, k) + view * 3);
}

Rgb FactoredMaterial::reflectance(int texel, int view, int light) const {
  Rgb terms[kMaxFactorTerms];
  term_values(texel, view, light, terms);
  Rgb sum = terms[0];
  for (int k = 1; k < state_.terms; ++k) sum += terms[k];
  return sum;
}

void FactoredMaterial::eval_lights(Vec2 uv, Vec3 view_local, std::span<Rgb> out,
                                   TexelFilter filter) const {
  const MaterialSampling& s = state_.sampling;
  const int m = s.light_count();
  PRT_CHECK(out.size() == static_cast<std::size_t>(m), "material {}: {} values for M = {}",
            state_.backend, out.size(), m);
  const Vec3 e = clamp_to_hemisphere(view_local);
  const BtfViewSamples views = btf_view_samples(s.view_side, e);
  const BtfTexelSamples texels = btf_texel_samples(s.resolution, uv, filter);
  std::fill(out.begin(), out.end(), Rgb(0.0f));
  // The texels' light-independent part of each term first, as the kernel folds it.
  const int terms = state_.terms;
  Rgb coef[4 * kMaxFactorTerms];
  for (int t = 0; t < texels.count; ++t)
    for (int k = 0; k < terms; ++k) {
      const float* r = r_entry(texels.texel[t], k);
      Rgb re(0.0f);
      for (int i = 0; i < 4; ++i) re += views.weight[i] * load3(r + views.view[i] * 3);
      coef[t * terms + k] = (texels.weight[t] * load3(scale_of(texels.texel[t], k))) * re;
    }
  for (int j = 0; j < m; ++j) {
    const BtfViewSamples h = halfway_samples(state_.half_side, lights_[j], e);
    Rgb sum(0.0f);
    for (int t = 0; t < texels.count; ++t) {
      const Rgb qv = interpolate_q(q_entry(texels.texel[t]), h, state_.interpolation);
      for (int k = 0; k < terms; ++k)
        sum += coef[t * terms + k] * load3(p_entry(texels.texel[t], k) + j * 3) * qv;
    }
    out[j] = sum;
  }
}

// ---- device ----

namespace {

class FactoredDeviceMaterial final : public DeviceMaterial {
 public:
  FactoredDeviceMaterial(ClContext& context, std::span<const FactoredMaterial* const> parts) {
    PRT_CHECK(!parts.empty(), "factored material: no parts to upload");
    const std::string& backend = parts.front()->backend();
    const int light_side = parts.front()->state().sampling.light_side;
    // The kernel addresses codebooks and texels with 32-bit offsets.
    const auto offset = [&](std::uint64_t v) {
      if (v > std::numeric_limits<cl_uint>::max())
        throw ParameterError(fmt::format(
            "material {}: the parts' codebooks and maps hold more than 2^32 values, which the "
            "shading kernel cannot address; use clusters > 0 or a smaller half_side",
            backend));
      return static_cast<cl_uint>(v);
    };
    std::map<const FactoredMaterial*, cl_uint> texel_base;
    std::vector<float> books;
    std::vector<cl_uint4> texels;
    std::vector<cl_float4> scales;
    std::vector<cl_int4> info;
    for (const FactoredMaterial* part : parts) {
      const auto& st = part->state();
      const MaterialSampling& s = st.sampling;
      if (s.light_side != light_side)
        throw ParameterError(fmt::format("material {}: the parts' light sides differ ({} and {})",
                                         backend, light_side, s.light_side));
      auto [it, fresh] = texel_base.emplace(part, offset(texels.size()));
      if (fresh) {
        const auto append = [&](const std::vector<float>& b) {
          const std::uint64_t at = books.size();
          books.insert(books.end(), b.begin(), b.end());
          return at;
        };
        const std::uint64_t p0 = append(st.codebook_p), q0 = append(st.codebook_q),
                            r0 = append(st.codebook_r);
        (void)offset(books.size());
        // One row per texel and term, a texel's terms consecutive, each with the texel's Q.
        for (int t = 0; t < s.texel_count(); ++t)
          for (int k = 0; k < st.terms; ++k) {
            const std::size_t row = static_cast<std::size_t>(t) * st.terms + k;
            texels.push_back(
                cl_uint4{{offset(p0 + std::uint64_t{st.index_p[row]} * s.light_count() * 3),
                          offset(q0 + std::uint64_t{st.index_q[t]} * part->half_count() * 3),
                          offset(r0 + std::uint64_t{st.index_r[row]} * s.view_count() * 3), 0u}});
            const float* sc = st.scale.data() + row * 3;
            scales.push_back(cl_float4{{sc[0], sc[1], sc[2], 0.0f}});
          }
        (void)offset(texels.size());
      }
      // The kernel reads half_side from the low 16 bits, the interpolation from bit 16 and the
      // terms from bits 20 to 23.
      PRT_CHECK(st.half_side < (1 << 16) && st.terms >= 1 && st.terms <= kMaxFactorTerms,
                "material {}: half side {} or {} terms out of the kernel's range", backend,
                st.half_side, st.terms);
      const cl_int geometric = st.interpolation == HalfwayInterpolation::kGeometric ? 1 : 0;
      info.push_back(
          cl_int4{{s.resolution, s.view_side, st.half_side | (geometric << 16) | (st.terms << 20),
                   static_cast<cl_int>(it->second)}});
      max_terms_ = std::max(max_terms_, st.terms);
      terms_.push_back(st.terms);
    }
    std::vector<cl_float4> lights;
    for (const Vec3& d : light_directions_f(light_side))
      lights.push_back(cl_float4{{d.x, d.y, d.z, 0.0f}});
    m_ = light_side * light_side;
    const std::string what = parts.front()->backend() + " material";
    books_ = upload(context, std::span<const float>(books), what + " codebooks");
    texels_ = upload(context, std::span<const cl_uint4>(texels), what + " index map");
    scales_ = upload(context, std::span<const cl_float4>(scales), what + " scale map");
    info_ = upload(context, std::span<const cl_int4>(info), what + " part table");
    lights_ = upload(context, std::span<const cl_float4>(lights), what + " light directions");
    bytes_ = books.size() * sizeof(float) + texels.size() * sizeof(cl_uint4) +
             scales.size() * sizeof(cl_float4) + info.size() * sizeof(cl_int4) +
             lights.size() * sizeof(cl_float4);
    label_ = parts.front()->backend();
  }

  std::string label() const override { return "factored_material.cl (" + label_ + ")"; }
  std::string source() const override { return std::string(kernel_source("factored_material")); }
  KernelDefines defines() const override { return {{"FM_TERMS", std::to_string(max_terms_)}}; }
  void set_args(cl::Kernel& kernel, unsigned first) const override {
    set_args_from(kernel, first, books_, texels_, scales_, info_, lights_);
  }
  std::uint64_t device_bytes() const override { return bytes_; }
  std::uint64_t bytes_per_hit(std::size_t part, TexelFilter filter) const override {
    const std::uint64_t texels = filter == TexelFilter::kBilinear ? 4 : 1;
    const auto k = static_cast<std::uint64_t>(terms_.at(part));
    // Per term the index and scale and R's 4 view samples, then per light each term's P and
    // Q's 4 halfway samples.
    return texels * (k * (32 + 4 * 12) + static_cast<std::uint64_t>(m_) * (k * 12 + 4 * 12)) +
           static_cast<std::uint64_t>(m_) * 16;
  }

 private:
  cl::Buffer books_, texels_, scales_, info_, lights_;
  std::string label_;
  int m_ = 0;
  int max_terms_ = 1;
  std::vector<int> terms_;  // per part
  std::uint64_t bytes_ = 0;
};

}  // namespace

std::unique_ptr<DeviceMaterial> FactoredMaterial::upload(
    ClContext& context, std::span<const CompressedMaterial* const> parts,
    const ParamSet& /*device_options*/) const {
  std::vector<const FactoredMaterial*> factored;
  for (const CompressedMaterial* p : parts) {
    const auto* f = dynamic_cast<const FactoredMaterial*>(p);
    if (!f)
      throw ParameterError(fmt::format("material {}: a part's material is '{}', not factored",
                                       backend(), p ? p->backend() : std::string("(none)")));
    factored.push_back(f);
  }
  return std::make_unique<FactoredDeviceMaterial>(context, factored);
}

// ---- archive ----

void FactoredMaterial::save(ArchiveWriter& w) const {
  const State& st = state_;
  const MaterialSampling& s = st.sampling;
  w.add_meta(kMetaKey, {{"format_version", kStateVersion},
                        {"backend", st.backend},
                        {"material", s.material},
                        {"resolution", s.resolution},
                        {"view_side", s.view_side},
                        {"light_side", s.light_side},
                        {"half_side", st.half_side},
                        {"terms", st.terms},
                        {"clusters", {st.clusters_p, st.clusters_q, st.clusters_r}},
                        {"quantized", st.quantized},
                        {"code_gamma", st.code_gamma},
                        {"halfway_interpolation", halfway_interpolation_name(st.interpolation)},
                        {"error", st.error},
                        {"parameters", st.parameters}});
  if (st.quantized) {
    w.add_section("codebook_p", st.codes_p);
    w.add_section("codebook_q", st.codes_q);
    w.add_section("codebook_r", st.codes_r);
    w.add_section("entry_scale_p", st.entry_scale_p);
    w.add_section("entry_scale_q", st.entry_scale_q);
    w.add_section("entry_scale_r", st.entry_scale_r);
    w.add_section("scale_map", st.scale_codes);
    w.add_section("scale_global", st.scale_global);
  } else {
    w.add_section("codebook_p", st.codebook_p);
    w.add_section("codebook_q", st.codebook_q);
    w.add_section("codebook_r", st.codebook_r);
    w.add_section("scale_map", st.scale);
  }
  // P's and R's indices and the scale map hold texels x terms rows.
  add_index_section(w, "index_p", st.index_p, static_cast<std::uint64_t>(st.clusters_p));
  add_index_section(w, "index_q", st.index_q, static_cast<std::uint64_t>(st.clusters_q));
  add_index_section(w, "index_r", st.index_r, static_cast<std::uint64_t>(st.clusters_r));
}

std::unique_ptr<FactoredMaterial> FactoredMaterial::load(const ArchiveReader& r,
                                                         const std::string& backend) {
  const auto fail = [&](const std::string& problem) {
    return InputError(r.path(), fmt::format("material {}: {}", backend, problem));
  };
  try {
    const auto meta = r.meta_value<nlohmann::json>(kMetaKey);
    const int version = meta.at("format_version").get<int>();
    if (version < 1 || version > static_cast<int>(kStateVersion))
      throw fail(fmt::format("state version {} is not 1 .. {}", meta.at("format_version").dump(),
                             kStateVersion));
    State st;
    st.backend = meta.at("backend").get<std::string>();
    if (st.backend != backend) throw fail(fmt::format("the state is of backend '{}'", st.backend));
    st.sampling = {meta.at("material").get<std::string>(), meta.at("resolution").get<int>(),
                   meta.at("view_side").get<int>(), meta.at("light_side").get<int>()};
    st.half_side = meta.at("half_side").get<int>();
    if (version >= 3) st.terms = meta.at("terms").get<int>();
    if (st.terms < 1 || st.terms > kMaxFactorTerms)
      throw fail(fmt::format("{} terms is not 1 .. {}", st.terms, kMaxFactorTerms));
    const auto& k = meta.at("clusters");
    st.clusters_p = k.at(0).get<int>();
    st.clusters_q = k.at(1).get<int>();
    st.clusters_r = k.at(2).get<int>();
    st.quantized = meta.at("quantized").get<bool>();
    st.code_gamma = meta.at("code_gamma").get<double>();
    if (!(st.code_gamma >= 1.0 && st.code_gamma <= 4.0))
      throw fail(fmt::format("code gamma {} is not in 1 .. 4", st.code_gamma));
    if (version >= 2) {
      const std::string mode = meta.at("halfway_interpolation").get<std::string>();
      if (mode == "geometric")
        st.interpolation = HalfwayInterpolation::kGeometric;
      else if (mode != "linear")
        throw fail(fmt::format("halfway interpolation '{}' is not 'linear' or 'geometric'", mode));
    }
    st.error = meta.at("error").get<double>();
    st.parameters = meta.at("parameters");
    const MaterialSampling& s = st.sampling;
    if (s.resolution < 1 || s.resolution > 4096 || s.view_side < 1 || s.view_side > 64 ||
        s.light_side < 1 || s.light_side > 64 || st.half_side < 1 || st.half_side > 256)
      throw fail(
          fmt::format("resolution {}, view side {}, light side {}, half side {} out of range",
                      s.resolution, s.view_side, s.light_side, st.half_side));
    const auto texels = static_cast<std::uint64_t>(s.texel_count());
    const std::uint64_t rows = texels * static_cast<std::uint64_t>(st.terms);
    for (const auto& [c, n] : {std::pair{st.clusters_p, rows}, std::pair{st.clusters_q, texels},
                               std::pair{st.clusters_r, rows}})
      if (c < 1 || static_cast<std::uint64_t>(c) > n)
        throw fail(fmt::format("a codebook of {} entries for {} factors", c, n));
    if (!(std::isfinite(st.error) && st.error >= 0)) throw fail("the stored error is not finite");
    const auto np = static_cast<std::uint64_t>(st.clusters_p) * s.light_count() * 3;
    const auto nq = static_cast<std::uint64_t>(st.clusters_q) * st.half_side * st.half_side * 3;
    const auto nr = static_cast<std::uint64_t>(st.clusters_r) * s.view_count() * 3;
    if (st.quantized) {
      st.codes_p = r.section<std::uint8_t>("codebook_p", np);
      st.codes_q = r.section<std::uint8_t>("codebook_q", nq);
      st.codes_r = r.section<std::uint8_t>("codebook_r", nr);
      st.entry_scale_p =
          r.section<float>("entry_scale_p", static_cast<std::uint64_t>(st.clusters_p));
      st.entry_scale_q =
          r.section<float>("entry_scale_q", static_cast<std::uint64_t>(st.clusters_q));
      st.entry_scale_r =
          r.section<float>("entry_scale_r", static_cast<std::uint64_t>(st.clusters_r));
      st.scale_codes = r.section<std::uint8_t>("scale_map", rows * 3);
      st.scale_global = r.section<float>("scale_global", 3);
      for (const auto* v :
           {&st.entry_scale_p, &st.entry_scale_q, &st.entry_scale_r, &st.scale_global})
        if (!std::all_of(v->begin(), v->end(), [](float x) { return std::isfinite(x) && x >= 0; }))
          throw fail("a quantisation scale is negative or not finite");
      st.codebook_p = decode(blocks(static_cast<std::size_t>(st.clusters_p), np / st.clusters_p,
                                    st.codes_p, st.entry_scale_p),
                             st.code_gamma);
      st.codebook_q = decode(blocks(static_cast<std::size_t>(st.clusters_q), nq / st.clusters_q,
                                    st.codes_q, st.entry_scale_q),
                             st.code_gamma);
      st.codebook_r = decode(blocks(static_cast<std::size_t>(st.clusters_r), nr / st.clusters_r,
                                    st.codes_r, st.entry_scale_r),
                             st.code_gamma);
      st.scale =
          decode_scale(static_cast<int>(rows), st.scale_codes, st.scale_global, st.code_gamma);
    } else {
      st.codebook_p = r.section<float>("codebook_p", np);
      st.codebook_q = r.section<float>("codebook_q", nq);
      st.codebook_r = r.section<float>("codebook_r", nr);
      st.scale = r.section<float>("scale_map", rows * 3);
      for (const auto* v : {&st.codebook_p, &st.codebook_q, &st.codebook_r, &st.scale})
        if (!std::all_of(v->begin(), v->end(), [](float x) { return std::isfinite(x) && x >= 0; }))
          throw fail("a factor or scale value is negative or not finite");
    }
    st.index_p = read_index_section(r, "index_p", rows, static_cast<std::uint64_t>(st.clusters_p));
    st.index_q =
        read_index_section(r, "index_q", texels, static_cast<std::uint64_t>(st.clusters_q));
    st.index_r = read_index_section(r, "index_r", rows, static_cast<std::uint64_t>(st.clusters_r));
    return std::make_unique<FactoredMaterial>(std::move(st));
  } catch (const nlohmann::json::exception& e) {
    throw fail(fmt::format("bad metadata ({})", e.what()));
  }
}

// ---- encoding ----

AbrdfFactors factor_texels(const Btf& btf, int half_count, const ChannelFactorizer& factor,
                           const std::string& backend, Progress& progress, int terms) {
  const int texels = btf.texel_count(), m = btf.light_count(), v = btf.view_count();
  PRT_CHECK(terms >= 1 && terms <= kMaxFactorTerms, "material {}: {} terms", backend, terms);
  AbrdfFactors out(texels, m, half_count, v, terms);
  std::atomic<int> bad{-1};  // the first texel * 3 + channel with a bad factor
  tbb::parallel_for(0, texels, [&](int t) {
    std::vector<double> f(static_cast<std::size_t>(m) * v), p(static_cast<std::size_t>(terms) * m),
        q(static_cast<std::size_t>(half_count)), r(static_cast<std::size_t>(terms) * v);
    const float* base = btf.data().data() + btf.offset(t, 0, 0);
    for (int c = 0; c < 3; ++c) {
      for (std::size_t s = 0; s < f.size(); ++s) f[s] = base[s * 3 + c];
      factor(f, p, q, r);
      const auto put = [&](std::vector<float>& dst, const std::vector<double>& src) {
        float* d = dst.data() + static_cast<std::size_t>(t) * src.size() * 3 + c;
        for (std::size_t i = 0; i < src.size(); ++i) {
          if (!(std::isfinite(src[i]) && src[i] >= 0)) {
            int none = -1;
            bad.compare_exchange_strong(none, t * 3 + c);
          }
          d[i * 3] = static_cast<float>(src[i]);
        }
      };
      put(out.p, p);
      put(out.q, q);
      put(out.r, r);
    }
    progress.advance(1);
  });
  if (bad >= 0)
    throw ParameterError(fmt::format(
        "material {}: a factor of texel {} channel {} of BTF '{}' is negative or not finite "
        "(a negative or non-finite BTF value, or for hf an ill-conditioned log system: raise "
        "lambda or floor)",
        backend, bad / 3, bad % 3, btf.material()));
  return out;
}

std::unique_ptr<FactoredMaterial> encode_factored_material(
    std::string backend, const Btf& full, int half_side, const AbrdfFactors& factors,
    const FactorCoding& coding, nlohmann::json parameters, FactorCodingTimes* times) {
  const int texels = full.texel_count();
  PRT_CHECK(factors.texels == texels && factors.light_count == full.light_count() &&
                factors.view_count == full.view_count() &&
                factors.half_count == half_side * half_side && factors.terms == coding.terms &&
                factors.terms >= 1 && factors.terms <= kMaxFactorTerms,
            "material {}: the factors do not match the BTF's sampling or the terms", backend);
  const int terms = factors.terms, rows = texels * terms;
  if (coding.clusters < 0)
    throw ParameterError(
        fmt::format("material {}: clusters {} is negative", backend, coding.clusters));
  std::vector<float> p = factors.p, q = factors.q, r = factors.r;
  const std::vector<float> mp = normalise(p, rows, factors.light_count);
  const std::vector<float> mq = normalise(q, texels, factors.half_count);
  const std::vector<float> mr = normalise(r, rows, factors.view_count);

  FactoredMaterial::State st;
  st.backend = backend;
  st.sampling = sampling_of(full);
  st.half_side = half_side;
  st.terms = terms;
  st.quantized = coding.quantize;
  st.code_gamma = coding.quantize ? coding.code_gamma : 1.0;
  st.interpolation = coding.interpolation;
  st.parameters = std::move(parameters);
  st.scale.resize(static_cast<std::size_t>(rows) * 3);
  for (std::size_t i = 0; i < st.scale.size(); ++i)
    st.scale[i] = mp[i] * mq[(i / 3 / terms) * 3 + i % 3] * mr[i];

  auto t0 = std::chrono::steady_clock::now();
  Codebook bp = cluster(p, rows, factors.light_count, coding, 0);
  Codebook bq = cluster(q, texels, factors.half_count, coding, 1);
  Codebook br = cluster(r, rows, factors.view_count, coding, 2);
  if (times) times->clustering_seconds = seconds_since(t0);
  st.clusters_p = bp.clusters;
  st.clusters_q = bq.clusters;
  st.clusters_r = br.clusters;
  st.index_p = std::move(bp.index);
  st.index_q = std::move(bq.index);
  st.index_r = std::move(br.index);
  t0 = std::chrono::steady_clock::now();
  if (coding.quantize) {
    quantize_codebook(bp.entries, bp.clusters, static_cast<std::size_t>(factors.light_count) * 3,
                      coding.code_gamma, st.codes_p, st.entry_scale_p);
    quantize_codebook(bq.entries, bq.clusters, static_cast<std::size_t>(factors.half_count) * 3,
                      coding.code_gamma, st.codes_q, st.entry_scale_q);
    quantize_codebook(br.entries, br.clusters, static_cast<std::size_t>(factors.view_count) * 3,
                      coding.code_gamma, st.codes_r, st.entry_scale_r);
  }
  if (times) times->quantization_seconds = seconds_since(t0);
  if (times)
    st.timings = {{"factorization_seconds", times->factorization_seconds},
                  {"clustering_seconds", times->clustering_seconds},
                  {"quantization_seconds", times->quantization_seconds},
                  {"abrdfs", texels},
                  {"samples_per_abrdf", full.light_count() * full.view_count()}};
  st.codebook_p = std::move(bp.entries);
  st.codebook_q = std::move(bq.entries);
  st.codebook_r = std::move(br.entries);
  if (coding.refit_scale) {
    // The scales that minimise each texel channel's squared error against the BTF with the
    // codebook entries it was given (each term's product g_k evaluated with scale 1 and the
    // material's halfway interpolation, since the copy keeps it), non-negative: coordinate
    // descent on the normal equations G s = b, G_kl = <g_k, g_l>, b_k = <f, g_k>, from the
    // normalisation's scales; one term takes s = max(<f, g> / <g, g>, 0) in its first sweep. The
    // maxima of the normalisation are the minimiser only for an unclustered, unquantised entry
    // of a factorisation that is itself least squares.
    FactoredMaterial::State unit = st;
    std::fill(unit.scale.begin(), unit.scale.end(), 1.0f);
    unit.quantized = false;
    const FactoredMaterial g(std::move(unit));
    tbb::parallel_for(0, texels, [&](int t) {
      constexpr int kk = kMaxFactorTerms;
      double gram[kk][kk][3] = {}, b[kk][3] = {};
      Rgb gv[kk];
      for (int v = 0; v < full.view_count(); ++v)
        for (int j = 0; j < full.light_count(); ++j) {
          g.term_values(t, v, j, gv);
          const Rgb fv = full.value(t, v, j);
          for (int k = 0; k < terms; ++k)
            for (int c = 0; c < 3; ++c) {
              b[k][c] += static_cast<double>(fv[c]) * gv[k][c];
              for (int l = 0; l < terms; ++l)
                gram[k][l][c] += static_cast<double>(gv[k][c]) * gv[l][c];
            }
        }
      float* out = st.scale.data() + static_cast<std::size_t>(t) * terms * 3;
      for (int c = 0; c < 3; ++c) {
        double x[kk];
        for (int k = 0; k < terms; ++k) x[k] = out[k * 3 + c];
        for (int sweep = 0; sweep < (terms == 1 ? 1 : kScaleSweeps); ++sweep) {
          double change = 0, size = 0;
          for (int k = 0; k < terms; ++k) {
            double rhs = b[k][c];
            for (int l = 0; l < terms; ++l)
              if (l != k) rhs -= gram[k][l][c] * x[l];
            const double next = gram[k][k][c] > 0 ? std::max(rhs / gram[k][k][c], 0.0) : 0.0;
            change = std::max(change, std::abs(next - x[k]));
            size = std::max(size, next);
            x[k] = next;
          }
          if (change <= kScaleTolerance * size) break;
        }
        for (int k = 0; k < terms; ++k) out[k * 3 + c] = static_cast<float>(x[k]);
      }
    });
  }
  if (coding.quantize)
    quantize_scale(st.scale, rows, st.code_gamma, st.scale_codes, st.scale_global);
  auto material = std::make_unique<FactoredMaterial>(st);
  st.error = material_error(*material, full).relative_l2;
  return std::make_unique<FactoredMaterial>(std::move(st));
}

}  // namespace prt

namespace prt {

std::unique_ptr<FactoredMaterial> compress_factored(const std::string& backend, const Btf& btf,
                                                    int half_side, const ChannelFactorizer& factor,
                                                    const FactorCoding& coding,
                                                    nlohmann::json parameters,
                                                    double setup_seconds) {
  const auto t0 = std::chrono::steady_clock::now();
  Progress bar(fmt::format("{}: factoring {} ABRDFs", backend, btf.texel_count()),
               btf.texel_count());
  const AbrdfFactors factors =
      factor_texels(btf, half_side * half_side, factor, backend, bar, coding.terms);
  bar.finish();
  FactorCodingTimes times;
  times.factorization_seconds = setup_seconds + seconds_since(t0);
  return encode_factored_material(backend, btf, half_side, factors, coding, std::move(parameters),
                                  &times);
}

}  // namespace prt

namespace prt {

FactorCoding factor_coding(const ParamSet& p) {
  FactorCoding c;
  c.half_side = static_cast<int>(p.get_int("half_side"));
  c.clusters = static_cast<int>(p.get_int("clusters"));
  c.quantize = p.get_bool("quantize");
  c.refit_scale = p.get_bool("refit_scale");
  c.code_gamma = p.get_real("code_gamma");
  c.seed = static_cast<std::uint64_t>(p.get_int("seed"));
  return c;
}

std::vector<ParamSpec> factor_coding_params() {
  return {{"half_side",
           ParamType::kInt,
           "16",
           2,
           64,
           {},
           "side of the halfway-vector grid Q is stored on (half_side^2 directions)"},
          {"clusters",
           ParamType::kInt,
           "256",
           0,
           65536,
           {},
           "codebook entries per factor set (at most the texel count; 256 fits the paper's "
           "8-bit index map); 0: no clustering, one factor per texel"},
          {"quantize",
           ParamType::kBool,
           "true",
           0,
           0,
           {},
           "store the codebooks and the scale map in 8 bits (the paper's textures)"},
          {"refit_scale",
           ParamType::kBool,
           "true",
           0,
           0,
           {},
           "after clustering, each texel's scale is the least-squares one for the codebook "
           "entries it got (not in the paper, which keeps the normalisation's maxima: false)"},
          {"code_gamma",
           ParamType::kReal,
           "2.2",
           1,
           4,
           {},
           "8-bit codes of the codebooks and the scale map are linear in x^(1/code_gamma): 1 is "
           "the paper's linear textures; 2.2 (the default, not in the paper) spends them like an "
           "sRGB texture, finer near 0, which factors of a high dynamic range need"}};
}

}  // namespace prt

namespace prt {

FactoredCompressor::FactoredCompressor(std::string backend, Setup setup, FactorCoding coding,
                                       nlohmann::json parameters)
    : backend_(std::move(backend)),
      setup_(std::move(setup)),
      coding_(coding),
      parameters_(std::move(parameters)) {}

std::unique_ptr<CompressedMaterial> FactoredCompressor::compress(const MaterialInput& input,
                                                                 Progress& progress) const {
  if (!input.btf) throw ParameterError(fmt::format("material {}: no BTF given", backend_));
  const auto t0 = std::chrono::steady_clock::now();
  const ChannelFactorizer factor = setup_(*input.btf);
  auto material = compress_factored(backend_, *input.btf, coding_.half_side, factor, coding_,
                                    parameters_, seconds_since(t0));
  progress.finish();
  return material;
}

}  // namespace prt

namespace prt {

std::function<std::unique_ptr<CompressedMaterial>(const ArchiveReader&)> factored_loader(
    std::string backend) {
  return [backend =
              std::move(backend)](const ArchiveReader& r) -> std::unique_ptr<CompressedMaterial> {
    return FactoredMaterial::load(r, backend);
  };
}

}  // namespace prt
