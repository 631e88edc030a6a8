#include "svd/svd_material.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "prtlab/base/error.h"
#include "prtlab/storage/archive.h"

namespace prt::svd {
namespace {

std::size_t floats_expected(Mode mode, const MaterialSampling& s, int rank, const char* which) {
  const auto k = static_cast<std::size_t>(rank);
  const auto texels = static_cast<std::size_t>(s.texel_count());
  const auto v = static_cast<std::size_t>(s.view_count());
  const auto m = static_cast<std::size_t>(s.light_count());
  const std::string_view w(which);
  if (mode == Mode::kAbrdf) {
    if (w == "view_factors") return texels * v * k * 3;
    if (w == "light_factors") return texels * k * m * 3;
    return 0;
  }
  if (w == "mean") return v * m * 3;
  if (w == "components") return k * v * m * 3;
  if (w == "coefficients") return texels * k;
  return 0;
}

constexpr const char* kSections[] = {"view_factors", "light_factors", "mean", "components",
                                     "coefficients"};

// The named array of a state, const or not.
template <typename State>
auto& section_of(State& s, std::string_view name) {
  if (name == "view_factors") return s.view_factors;
  if (name == "light_factors") return s.light_factors;
  if (name == "mean") return s.mean;
  if (name == "components") return s.components;
  return s.coefficients;
}

inline Rgb load3(const float* p) {
  return {p[0], p[1], p[2]};
}

}  // namespace

std::string_view mode_name(Mode m) {
  return m == Mode::kAbrdf ? "abrdf" : "texel_pca";
}

Mode mode_from(std::string_view name) {
  if (name == "abrdf") return Mode::kAbrdf;
  if (name == "texel_pca") return Mode::kTexelPca;
  throw ParameterError(fmt::format("material svd: mode '{}' is not one of abrdf, texel_pca", name));
}

SvdMaterial::SvdMaterial(SvdState state) : state_(std::move(state)) {
  const MaterialSampling& s = state_.sampling;
  if (s.texel_count() < 1 || s.view_count() < 1 || s.light_count() < 1 || state_.rank < 1)
    throw ParameterError(fmt::format("material svd: sampling {} x {} x {} or rank {} is empty",
                                     s.resolution, s.view_side, s.light_side, state_.rank));
  for (const char* name : kSections) {
    const std::size_t want = floats_expected(state_.mode, s, state_.rank, name);
    const std::size_t have = section_of(state_, name).size();
    if (want != have)
      throw ParameterError(fmt::format("material svd ({}): {} holds {} floats, not {}",
                                       mode_name(state_.mode), name, have, want));
  }
}

std::size_t SvdMaterial::view_floats_per_texel() const {
  return static_cast<std::size_t>(state_.sampling.view_count()) * state_.rank * 3;
}

std::size_t SvdMaterial::light_floats_per_texel() const {
  return static_cast<std::size_t>(state_.rank) * state_.sampling.light_count() * 3;
}

double SvdMaterial::declared_error_bound() const {
  return state_.total > 0 ? std::sqrt(std::max(state_.discarded, 0.0) / state_.total) : 0.0;
}

StorageReport SvdMaterial::storage() const {
  StorageReport r;
  const auto f32 = [](const std::vector<float>& v) { return v.size() * sizeof(float); };
  if (state_.mode == Mode::kAbrdf) {
    r.components.push_back({"view_factors", f32(state_.view_factors),
                            "f32 U_r(view) per texel and channel: [((texel V + view) K + r) 3 + "
                            "channel], unit columns"});
    r.components.push_back({"light_factors", f32(state_.light_factors),
                            "f32 sigma_r V_r(light) per texel and channel: [((texel K + r) M + "
                            "light) 3 + channel]"});
  } else {
    r.components.push_back({"mean", f32(state_.mean),
                            "f32 mean ABRDF over the texels: [view 3M + 3 light + channel]"});
    r.components.push_back({"components", f32(state_.components),
                            "f32 K orthonormal principal directions: [(r V + view) 3M + 3 light + "
                            "channel]"});
    r.components.push_back(
        {"coefficients", f32(state_.coefficients), "f32 K coefficients per texel: [texel K + r]"});
  }
  return r;
}

double SvdMaterial::flops_per_pixel() const {
  const double m = state_.sampling.light_count(), k = state_.rank;
  if (state_.mode == Mode::kAbrdf) {
    // The view factors at the view (4 samples x K), then b_j = sum_r a_r W_r(j) and the dot
    // product with L*.
    return 2.0 * 4.0 * k + 2.0 * k * m + 2.0 * m;
  }
  // The texel's K coefficients (shared by the channels), then per view sample and light the
  // mean and K components, and the dot product.
  return 2.0 * 4.0 * (k + 1.0) * m + 2.0 * m;
}

Rgb SvdMaterial::reflectance(int texel, int view, int light) const {
  const MaterialSampling& s = state_.sampling;
  PRT_CHECK(texel >= 0 && texel < s.texel_count() && view >= 0 && view < s.view_count() &&
                light >= 0 && light < s.light_count(),
            "material svd: sample ({}, {}, {}) out of range", texel, view, light);
  const auto k = static_cast<std::size_t>(state_.rank);
  const auto m = static_cast<std::size_t>(s.light_count());
  const auto t = static_cast<std::size_t>(texel);
  Rgb out(0.0f);
  if (state_.mode == Mode::kAbrdf) {
    const float* u = state_.view_factors.data() + t * view_floats_per_texel() +
                     static_cast<std::size_t>(view) * k * 3;
    const float* w = state_.light_factors.data() + t * light_floats_per_texel() +
                     static_cast<std::size_t>(light) * 3;
    for (std::size_t r = 0; r < k; ++r) out += load3(u + r * 3) * load3(w + r * m * 3);
    return out;
  }
  const std::size_t row = static_cast<std::size_t>(s.view_count()) * m * 3;
  const std::size_t at =
      static_cast<std::size_t>(view) * m * 3 + static_cast<std::size_t>(light) * 3;
  out = load3(state_.mean.data() + at);
  const float* a = state_.coefficients.data() + t * k;
  for (std::size_t r = 0; r < k; ++r) out += a[r] * load3(state_.components.data() + r * row + at);
  return out;
}

void SvdMaterial::eval_abrdf(const BtfTexelSamples& ts, const BtfViewSamples& vs,
                             std::span<Rgb> out) const {
  const auto k = static_cast<std::size_t>(state_.rank);
  const auto m = static_cast<std::size_t>(state_.sampling.light_count());
  std::vector<Rgb> a(k);
  for (int t = 0; t < ts.count; ++t) {
    const auto texel = static_cast<std::size_t>(ts.texel[t]);
    const float* u = state_.view_factors.data() + texel * view_floats_per_texel();
    const float* w = state_.light_factors.data() + texel * light_floats_per_texel();
    // The view factors interpolated at the view, with the texel's weight folded in, as svd.cl.
    for (std::size_t r = 0; r < k; ++r) {
      Rgb sum(0.0f);
      for (int q = 0; q < 4; ++q)
        sum += vs.weight[q] * load3(u + (static_cast<std::size_t>(vs.view[q]) * k + r) * 3);
      a[r] = ts.weight[t] * sum;
    }
    for (std::size_t j = 0; j < m; ++j) {
      Rgb b(0.0f);
      for (std::size_t r = 0; r < k; ++r) b += a[r] * load3(w + (r * m + j) * 3);
      out[j] += b;
    }
  }
}

void SvdMaterial::eval_pca(const BtfTexelSamples& ts, const BtfViewSamples& vs,
                           std::span<Rgb> out) const {
  const auto k = static_cast<std::size_t>(state_.rank);
  const auto m = static_cast<std::size_t>(state_.sampling.light_count());
  const std::size_t row = static_cast<std::size_t>(state_.sampling.view_count()) * m * 3;
  // The texels' coefficients mixed first (the texel weights sum to 1, so the mean enters once).
  std::vector<float> a(k, 0.0f);
  for (int t = 0; t < ts.count; ++t) {
    const float* c = state_.coefficients.data() + static_cast<std::size_t>(ts.texel[t]) * k;
    for (std::size_t r = 0; r < k; ++r) a[r] += ts.weight[t] * c[r];
  }
  for (int q = 0; q < 4; ++q) {
    const float w = vs.weight[q];
    if (w == 0.0f) continue;
    const std::size_t base = static_cast<std::size_t>(vs.view[q]) * m * 3;
    for (std::size_t j = 0; j < m; ++j) {
      Rgb b = load3(state_.mean.data() + base + j * 3);
      for (std::size_t r = 0; r < k; ++r)
        b += a[r] * load3(state_.components.data() + r * row + base + j * 3);
      out[j] += w * b;
    }
  }
}

void SvdMaterial::eval_lights(Vec2 uv, Vec3 view_local, std::span<Rgb> out,
                              TexelFilter filter) const {
  const MaterialSampling& s = state_.sampling;
  PRT_CHECK(out.size() == static_cast<std::size_t>(s.light_count()),
            "material svd: {} values for M = {}", out.size(), s.light_count());
  const BtfTexelSamples ts = btf_texel_samples(s.resolution, uv, filter);
  const BtfViewSamples vs = btf_view_samples(s.view_side, view_local);
  std::fill(out.begin(), out.end(), Rgb(0.0f));
  if (state_.mode == Mode::kAbrdf)
    eval_abrdf(ts, vs, out);
  else
    eval_pca(ts, vs, out);
}

std::unique_ptr<DeviceMaterial> SvdMaterial::upload(
    ClContext& context, std::span<const CompressedMaterial* const> parts,
    const ParamSet& /*device_options*/) const {
  std::vector<const SvdMaterial*> svd;
  for (const CompressedMaterial* p : parts) {
    const auto* f = dynamic_cast<const SvdMaterial*>(p);
    if (!f)
      throw ParameterError(fmt::format("material svd: a part's material is '{}', not svd",
                                       p ? p->backend() : std::string("(none)")));
    svd.push_back(f);
  }
  return upload_svd(context, svd);
}

void SvdMaterial::save(ArchiveWriter& w) const {
  const MaterialSampling& s = state_.sampling;
  w.add_meta(std::string(kName), {{"format_version", kStateVersion},
                                  {"mode", std::string(mode_name(state_.mode))},
                                  {"rank", state_.rank},
                                  {"material", s.material},
                                  {"resolution", s.resolution},
                                  {"view_side", s.view_side},
                                  {"light_side", s.light_side},
                                  {"discarded", state_.discarded},
                                  {"total", state_.total},
                                  {"parameters", state_.parameters}});
  for (const char* name : kSections)
    if (floats_expected(state_.mode, s, state_.rank, name) > 0)
      w.add_section(name, section_of(state_, name));
}

std::unique_ptr<CompressedMaterial> SvdMaterial::load(const ArchiveReader& r) {
  SvdState s;
  try {
    const auto meta = r.meta_value<nlohmann::json>(std::string(kName));
    const int version = meta.at("format_version").get<int>();
    if (version != kStateVersion)
      throw InputError(r.path(), fmt::format("material svd: state version {} is not {}", version,
                                             kStateVersion));
    try {
      s.mode = mode_from(meta.at("mode").get<std::string>());
    } catch (const ParameterError& e) {
      throw InputError(r.path(), e.what());
    }
    s.rank = meta.at("rank").get<int>();
    s.sampling.material = meta.at("material").get<std::string>();
    s.sampling.resolution = meta.at("resolution").get<int>();
    s.sampling.view_side = meta.at("view_side").get<int>();
    s.sampling.light_side = meta.at("light_side").get<int>();
    s.discarded = meta.at("discarded").get<double>();
    s.total = meta.at("total").get<double>();
    s.parameters = meta.at("parameters");
    const MaterialSampling& m = s.sampling;
    if (m.resolution < 1 || m.resolution > 4096 || m.view_side < 1 || m.view_side > 64 ||
        m.light_side < 1 || m.light_side > 64)
      throw InputError(r.path(),
                       fmt::format("material svd: resolution {}, view side {}, light side {} out "
                                   "of range",
                                   m.resolution, m.view_side, m.light_side));
    const int max_rank = s.mode == Mode::kAbrdf
                             ? std::min(m.view_count(), m.light_count())
                             : std::min(m.texel_count(), 3 * m.view_count() * m.light_count());
    if (s.rank < 1 || s.rank > max_rank)
      throw InputError(r.path(), fmt::format("material svd: rank {} is outside [1, {}] for mode {}",
                                             s.rank, max_rank, mode_name(s.mode)));
    if (!std::isfinite(s.discarded) || !std::isfinite(s.total) || s.discarded < 0 || s.total < 0)
      throw InputError(r.path(), fmt::format("material svd: residual {} or norm {} is not a "
                                             "finite non-negative number",
                                             s.discarded, s.total));
    for (const char* name : kSections) {
      const std::size_t want = floats_expected(s.mode, m, s.rank, name);
      if (want == 0) continue;
      std::vector<float>& v = section_of(s, name);
      v = r.section<float>(name, want);
      for (const float x : v)
        if (!std::isfinite(x))
          throw InputError(r.path(),
                           fmt::format("material svd: section {} holds a non-finite value", name));
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(r.path(), fmt::format("material svd: bad metadata ({})", e.what()));
  }
  return std::make_unique<SvdMaterial>(std::move(s));
}

}  // namespace prt::svd
