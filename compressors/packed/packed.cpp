#include "packed/packed.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "prtlab/base/error.h"
#include "prtlab/numeric/float16.h"
#include "prtlab/storage/archive.h"

namespace prt::packed {
namespace {

constexpr float kHalfMax = 65504.0f;
// Half of float16's subnormal spacing 2^-24: the largest rounding error of a value below the
// normal range.
constexpr float kHalfSubnormalError = 0x1p-25f;
constexpr float kHalfRelativeError = 0x1p-11f;

class PackedCompressor final : public MaterialCompressor {
 public:
  PackedCompressor(Storage storage, int tile) : storage_(storage), tile_(tile) {}
  std::unique_ptr<CompressedMaterial> compress(const MaterialInput& input,
                                               Progress& progress) const override {
    if (!input.btf) throw ParameterError("material packed: no BTF given");
    auto out = std::make_unique<PackedMaterial>(*input.btf, storage_, tile_);
    progress.finish();
    return out;
  }

 private:
  Storage storage_;
  int tile_;
};

Storage storage_from(const std::string& s) {
  if (s == "f16") return Storage::kHalf;
  if (s == "u8") return Storage::kByte;
  throw ParameterError(fmt::format("material packed: storage '{}' is not f16 or u8", s));
}

}  // namespace

std::string_view storage_name(Storage s) {
  return s == Storage::kHalf ? "f16" : "u8";
}

std::vector<std::int32_t> tiled_texel_slots(int res, int tile) {
  PRT_CHECK(res >= 1 && tile >= 1, "tiled_texel_slots: resolution {} and tile {} must be >= 1", res,
            tile);
  std::vector<std::int32_t> slot(static_cast<std::size_t>(res) * res, -1);
  std::int32_t next = 0;
  for (int ty = 0; ty < res; ty += tile)
    for (int tx = 0; tx < res; tx += tile)
      for (int y = ty; y < std::min(ty + tile, res); ++y)
        for (int x = tx; x < std::min(tx + tile, res); ++x)
          slot[static_cast<std::size_t>(y) * res + x] = next++;
  return slot;
}

PackedMaterial::PackedMaterial(const Btf& btf, Storage storage, int tile)
    : sampling_(sampling_of(btf)),
      btf_parameters_(btf.parameters()),
      storage_(storage),
      tile_(tile) {
  if (tile < 1 || tile > 4096)
    throw ParameterError(fmt::format("material packed: tile {} must be in [1, 4096]", tile));
  stored_views_ = btf.view_independent() ? 1 : btf.view_count();
  slot_ = tiled_texel_slots(btf.resolution(), tile);
  const std::size_t len = static_cast<std::size_t>(btf.light_count()) * 3;
  const std::size_t vectors = static_cast<std::size_t>(btf.texel_count()) * stored_views_;
  if (storage == Storage::kHalf)
    half_.resize(vectors * len);
  else {
    byte_.resize(vectors * len);
    scale_.resize(vectors);
  }
  for (int t = 0; t < btf.texel_count(); ++t) {
    for (int v = 0; v < stored_views_; ++v) {
      const std::span<const float> src = btf.light_vector(t, v);
      const std::size_t vec = vector_index(t, v);
      float peak = 0.0f;
      for (std::size_t k = 0; k < len; ++k) {
        const float x = src[k];
        if (!std::isfinite(x) || x < 0.0f)
          throw ParameterError(fmt::format(
              "material packed: BTF '{}' has the value {} at texel {}, view {}, light {}, "
              "channel {}; packed storage needs finite non-negative reflectance",
              btf.material(), x, t, v, k / 3, k % 3));
        peak = std::max(peak, x);
      }
      if (storage == Storage::kHalf) {
        if (peak > kHalfMax)
          throw ParameterError(fmt::format(
              "material packed: BTF '{}' has the value {} at texel {}, view {}, beyond float16's "
              "range (65504); use storage=u8",
              btf.material(), peak, t, v));
        for (std::size_t k = 0; k < len; ++k) half_[vec * len + k] = float_to_half(src[k]);
      } else {
        const float s = peak / 255.0f;
        scale_[vec] = s;
        for (std::size_t k = 0; k < len; ++k) {
          const float q = s > 0.0f ? std::nearbyint(src[k] / s) : 0.0f;
          byte_[vec * len + k] = static_cast<std::uint8_t>(std::clamp(q, 0.0f, 255.0f));
        }
      }
    }
  }
  compute_error_bound(&btf);
}

float PackedMaterial::decoded(std::size_t vector, int k) const {
  const std::size_t len = static_cast<std::size_t>(sampling_.light_count()) * 3;
  const std::size_t i = vector * len + static_cast<std::size_t>(k);
  return storage_ == Storage::kHalf ? half_to_float(half_[i])
                                    : scale_[vector] * static_cast<float>(byte_[i]);
}

float PackedMaterial::value_error_bound(int texel, int view, int k) const {
  const std::size_t vec = vector_index(texel, view);
  if (storage_ == Storage::kByte) return 0.5f * scale_[vec];
  const float v = decoded(vec, k);
  // |v - h| <= 2^-11 |v| <= 2^-11 |h| / (1 - 2^-11) for normal values.
  return kHalfRelativeError * v / (1.0f - kHalfRelativeError) + kHalfSubnormalError;
}

void PackedMaterial::compute_error_bound(const Btf* /*original*/) {
  // From the stored data alone (so a loaded material declares the same): the per-value bounds
  // summed in squares over all values, E, against the stored values' squares, D. The original's
  // norm is at least sqrt(D) - sqrt(E) (triangle inequality), so the relative L2 error is at most
  // sqrt(E) / (sqrt(D) - sqrt(E)).
  const int len = sampling_.light_count() * 3;
  double e = 0.0, d = 0.0;
  for (int t = 0; t < sampling_.texel_count(); ++t) {
    for (int v = 0; v < stored_views_; ++v) {
      const std::size_t vec = vector_index(t, v);
      for (int k = 0; k < len; ++k) {
        const double b = value_error_bound(t, v, k), x = decoded(vec, k);
        e += b * b;
        d += x * x;
      }
    }
  }
  const double se = std::sqrt(e), sd = std::sqrt(d);
  error_bound_ = sd > se ? se / (sd - se) : std::numeric_limits<double>::infinity();
  if (d == 0.0) error_bound_ = 0.0;
}

StorageReport PackedMaterial::storage() const {
  StorageReport r;
  if (storage_ == Storage::kHalf) {
    r.components.push_back({"f16", half_.size() * sizeof(std::uint16_t),
                            "IEEE binary16 per value, codes[(slot * V' + view) * 3M + 3 light + "
                            "channel], slot = tiled texel order"});
  } else {
    r.components.push_back(
        {"u8", byte_.size(), "8-bit code per value, v = scale[vector] * code, same order as f16"});
    r.components.push_back(
        {"scales", scale_.size() * sizeof(float), "f32 per (texel, view) vector: max / 255"});
  }
  // The texel slots are recomputed from `tile` on load (and uploaded with the codes): not stored.
  return r;
}

double PackedMaterial::flops_per_pixel() const {
  // As `full` (the decode of a code is one multiply folded into the pair's weight for u8, a
  // conversion for f16; neither counted, as the papers count multiply-adds).
  const double m = sampling_.light_count();
  const double samples = stored_views_ == 1 ? 1.0 : 4.0;
  return 2.0 * samples * m + 2.0 * m;
}

Rgb PackedMaterial::reflectance(int texel, int view, int light) const {
  PRT_CHECK(texel >= 0 && texel < sampling_.texel_count() && view >= 0 &&
                view < sampling_.view_count() && light >= 0 && light < sampling_.light_count(),
            "material packed: sample ({}, {}, {}) out of range", texel, view, light);
  const std::size_t vec = vector_index(texel, view);
  return {decoded(vec, 3 * light), decoded(vec, 3 * light + 1), decoded(vec, 3 * light + 2)};
}

void PackedMaterial::eval_lights(Vec2 uv, Vec3 view_local, std::span<Rgb> out,
                                 TexelFilter filter) const {
  const int m = sampling_.light_count();
  PRT_CHECK(out.size() == static_cast<std::size_t>(m), "need {} outputs, got {}", m, out.size());
  const BtfTexelSamples ts = btf_texel_samples(sampling_.resolution, uv, filter);
  BtfViewSamples vs;
  if (stored_views_ == 1) {
    vs.weight = {1.0f, 0.0f, 0.0f, 0.0f};
  } else {
    vs = btf_view_samples(sampling_.view_side, view_local);
  }
  std::fill(out.begin(), out.end(), Rgb(0.0f));
  const std::size_t len = static_cast<std::size_t>(m) * 3;
  for (int t = 0; t < ts.count; ++t) {
    for (int k = 0; k < 4; ++k) {
      const float w = ts.weight[t] * vs.weight[k];
      if (w == 0.0f) continue;
      const std::size_t vec = vector_index(ts.texel[t], vs.view[k]);
      if (storage_ == Storage::kHalf) {
        const std::uint16_t* p = half_.data() + vec * len;
        for (int j = 0; j < m; ++j)
          out[j] += w * Rgb(half_to_float(p[3 * j]), half_to_float(p[3 * j + 1]),
                            half_to_float(p[3 * j + 2]));
      } else {
        const float ws = w * scale_[vec];
        const std::uint8_t* p = byte_.data() + vec * len;
        for (int j = 0; j < m; ++j)
          out[j] += ws * Rgb(static_cast<float>(p[3 * j]), static_cast<float>(p[3 * j + 1]),
                             static_cast<float>(p[3 * j + 2]));
      }
    }
  }
}

std::unique_ptr<DeviceMaterial> PackedMaterial::upload(
    ClContext& context, std::span<const CompressedMaterial* const> parts,
    const ParamSet& /*device_options*/) const {
  std::vector<const PackedMaterial*> packed;
  for (const CompressedMaterial* p : parts) {
    const auto* f = dynamic_cast<const PackedMaterial*>(p);
    if (!f)
      throw ParameterError(fmt::format("material packed: a part's material is '{}', not packed",
                                       p ? p->backend() : std::string("(none)")));
    packed.push_back(f);
  }
  return upload_packed(context, packed);
}

void PackedMaterial::save(ArchiveWriter& w) const {
  w.add_meta(std::string(kName), {{"format_version", kStateVersion},
                                  {"material", sampling_.material},
                                  {"resolution", sampling_.resolution},
                                  {"view_side", sampling_.view_side},
                                  {"light_side", sampling_.light_side},
                                  {"storage", std::string(storage_name(storage_))},
                                  {"tile", tile_},
                                  {"stored_views", stored_views_},
                                  {"parameters", btf_parameters_}});
  if (storage_ == Storage::kHalf) {
    w.add_section("f16", half_);
  } else {
    w.add_section("u8", byte_);
    w.add_section("scales", scale_);
  }
}

std::unique_ptr<CompressedMaterial> PackedMaterial::load(const ArchiveReader& r) {
  const auto meta = r.meta_value<nlohmann::json>(std::string(kName));
  std::unique_ptr<PackedMaterial> m(new PackedMaterial());
  try {
    const int version = meta.at("format_version").get<int>();
    if (version != kStateVersion)
      throw InputError(r.path(), fmt::format("material packed: state version {} is not {}", version,
                                             kStateVersion));
    m->sampling_.material = meta.at("material").get<std::string>();
    m->sampling_.resolution = meta.at("resolution").get<int>();
    m->sampling_.view_side = meta.at("view_side").get<int>();
    m->sampling_.light_side = meta.at("light_side").get<int>();
    m->tile_ = meta.at("tile").get<int>();
    m->stored_views_ = meta.at("stored_views").get<int>();
    m->btf_parameters_ = meta.at("parameters");
    const MaterialSampling& s = m->sampling_;
    if (s.resolution < 1 || s.resolution > 4096 || s.view_side < 1 || s.view_side > 64 ||
        s.light_side < 1 || s.light_side > 64 || m->tile_ < 1 || m->tile_ > 4096 ||
        (m->stored_views_ != 1 && m->stored_views_ != s.view_count()))
      throw InputError(r.path(), fmt::format("material packed: resolution {}, view side {}, "
                                             "light side {}, tile {}, stored views {} out of range",
                                             s.resolution, s.view_side, s.light_side, m->tile_,
                                             m->stored_views_));
    try {
      m->storage_ = storage_from(meta.at("storage").get<std::string>());
    } catch (const ParameterError& e) {
      throw InputError(r.path(), e.what());
    }
    const std::uint64_t vectors =
        static_cast<std::uint64_t>(s.texel_count()) * static_cast<std::uint64_t>(m->stored_views_);
    const std::uint64_t count = vectors * static_cast<std::uint64_t>(s.light_count()) * 3;
    if (m->storage_ == Storage::kHalf) {
      m->half_ = r.section<std::uint16_t>("f16", count);
      for (const std::uint16_t h : m->half_)
        if ((h & 0x7c00u) == 0x7c00u || ((h & 0x8000u) != 0 && (h & 0x7fffu) != 0))
          throw InputError(r.path(),
                           "material packed: a float16 value is negative, infinite "
                           "or NaN");
    } else {
      m->byte_ = r.section<std::uint8_t>("u8", count);
      m->scale_ = r.section<float>("scales", vectors);
      for (const float sc : m->scale_)
        if (!std::isfinite(sc) || sc < 0.0f)
          throw InputError(r.path(), fmt::format("material packed: scale {} is not a finite "
                                                 "non-negative number",
                                                 sc));
    }
    m->slot_ = tiled_texel_slots(s.resolution, m->tile_);
    m->compute_error_bound(nullptr);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(r.path(), fmt::format("material packed: bad metadata ({})", e.what()));
  }
  return m;
}

MaterialEntry registry_entry() {
  MaterialEntry e;
  e.name = std::string(kName);
  e.description =
      "the sampled BTF in float16 or in 8-bit codes with one scale per (texel, view) vector "
      "(the central paper's 8-bit BTFs), texels stored in tiles: fewer bytes per shaded pixel";
  e.params = {
      {"storage",
       ParamType::kString,
       "u8",
       {},
       {},
       {"f16", "u8"},
       "f16: IEEE binary16 per value (relative error <= 2^-11); u8: an 8-bit code per "
       "value and one f32 scale per (texel, view) vector (error <= scale / 2)"},
      {"tile",
       ParamType::kInt,
       "4",
       1,
       4096,
       {},
       "texels are stored in tile x tile blocks (1: row-major), views of a texel adjacent"}};
  e.lossless = false;
  e.create = [](const ParamSet& p) -> std::unique_ptr<MaterialCompressor> {
    return std::make_unique<PackedCompressor>(storage_from(p.get_string("storage")),
                                              static_cast<int>(p.get_int("tile")));
  };
  e.load = &PackedMaterial::load;
  return e;
}

PRT_REGISTER_MATERIAL(registry_entry);

}  // namespace prt::packed
