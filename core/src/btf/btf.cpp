#include "prtlab/btf/btf.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>

#include "prtlab/base/error.h"
#include "prtlab/sphere/hemisphere_grid.h"

namespace prt {

namespace {

constexpr float kPiF = std::numbers::pi_v<float>;
constexpr float kQuarterPiF = 0.25f * kPiF;

// x mod 1 in [0, 1]; 0 for a non-finite x (a float-to-int conversion of NaN would be undefined).
float fract(float x) {
  const float f = x - std::floor(x);
  return std::isfinite(f) ? f : 0.0f;
}

int wrap(int i, int n) {
  const int r = i % n;
  return r < 0 ? r + n : r;
}

// Position along one axis of the 2 x 2 sample neighbourhood: the two sample columns (or rows)
// around square coordinate `s`, clamped at the square's edge.
struct AxisCell {
  int i0, i1;
};
AxisCell axis_cell(float s, int side) {
  const int i = static_cast<int>(std::floor(s * static_cast<float>(side) - 0.5f));
  return {std::clamp(i, 0, side - 1), std::clamp(i + 1, 0, side - 1)};
}

float sample_centre(int i, int side) {
  return (static_cast<float>(i) + 0.5f) / static_cast<float>(side);
}

// tx of btf_view_samples: chordal distances from e to the two sample lines along the curve
// through e. p0, p1 are the points of that curve on the two sample lines.
float sphere_fraction(const Vec3& e, const Vec3& p0, const Vec3& p1) {
  const float d0 = glm::length(e - p0), d1 = glm::length(e - p1);
  const float sum = d0 + d1;
  return sum > 0.0f ? d0 / sum : 0.0f;
}

}  // namespace

// --- float concentric map -------------------------------------------------------------------

Vec3 square_to_hemisphere_f(Vec2 ab) {
  const float u = 2.0f * ab.x - 1.0f, v = 2.0f * ab.y - 1.0f;
  if (u == 0.0f && v == 0.0f) return {0.0f, 0.0f, 1.0f};
  float r, phi;
  if (std::abs(u) > std::abs(v)) {
    r = u;
    phi = kQuarterPiF * (v / u);
  } else {
    r = v;
    phi = 2.0f * kQuarterPiF - kQuarterPiF * (u / v);
  }
  const float r2 = std::min(r * r, 1.0f);
  const float f = std::sqrt(2.0f - r2);
  return {r * std::cos(phi) * f, r * std::sin(phi) * f, 1.0f - r2};
}

Vec2 hemisphere_to_square_f(Vec3 d) {
  const float inv = 1.0f / std::sqrt(1.0f + std::abs(d.z));
  const float x = d.x * inv, y = d.y * inv;
  const float r = std::sqrt(x * x + y * y);
  if (r == 0.0f) return {0.5f, 0.5f};
  float phi = std::atan2(y, x);
  if (phi < -kQuarterPiF) phi += 2.0f * kPiF;
  float u, v;
  if (phi < kQuarterPiF) {
    u = r;
    v = phi / kQuarterPiF * u;
  } else if (phi < 3.0f * kQuarterPiF) {
    v = r;
    u = (2.0f * kQuarterPiF - phi) / kQuarterPiF * v;
  } else if (phi < 5.0f * kQuarterPiF) {
    u = -r;
    v = (phi - 4.0f * kQuarterPiF) / kQuarterPiF * u;
  } else {
    v = -r;
    u = (6.0f * kQuarterPiF - phi) / kQuarterPiF * v;
  }
  return {0.5f * (u + 1.0f), 0.5f * (v + 1.0f)};
}

Vec3 clamp_to_hemisphere(Vec3 d) {
  if (!std::isfinite(d.x) || !std::isfinite(d.y) || !std::isfinite(d.z)) return {0.f, 0.f, 1.f};
  if (d.x == 0.0f && d.y == 0.0f) return d.z < 0.0f ? Vec3(1.f, 0.f, 0.f) : Vec3(0.f, 0.f, 1.f);
  d.z = std::max(d.z, 0.0f);
  return glm::normalize(d);
}

BtfViewSamples btf_view_samples(int view_side, Vec3 view_local) {
  const Vec3 e = clamp_to_hemisphere(view_local);
  const Vec2 ab = hemisphere_to_square_f(e);
  const AxisCell cx = axis_cell(ab.x, view_side), cy = axis_cell(ab.y, view_side);
  float tx = 0.0f, ty = 0.0f;
  if (cx.i0 != cx.i1)
    tx = sphere_fraction(e, square_to_hemisphere_f({sample_centre(cx.i0, view_side), ab.y}),
                         square_to_hemisphere_f({sample_centre(cx.i1, view_side), ab.y}));
  if (cy.i0 != cy.i1)
    ty = sphere_fraction(e, square_to_hemisphere_f({ab.x, sample_centre(cy.i0, view_side)}),
                         square_to_hemisphere_f({ab.x, sample_centre(cy.i1, view_side)}));
  BtfViewSamples s;
  s.view = {cy.i0 * view_side + cx.i0, cy.i0 * view_side + cx.i1, cy.i1 * view_side + cx.i0,
            cy.i1 * view_side + cx.i1};
  s.weight = {(1.0f - tx) * (1.0f - ty), tx * (1.0f - ty), (1.0f - tx) * ty, tx * ty};
  return s;
}

// --- Btf ------------------------------------------------------------------------------------

Btf::Btf(std::string material, int resolution, int view_side, int light_side,
         std::vector<float> rgb, nlohmann::json parameters, ViewSkip skip)
    : material_(std::move(material)),
      resolution_(resolution),
      view_side_(view_side),
      light_side_(light_side),
      rgb_(std::move(rgb)),
      parameters_(std::move(parameters)) {
  if (resolution < 1 || resolution > 4096 || view_side < 1 || view_side > 64 || light_side < 1 ||
      light_side > 64)
    throw ParameterError(
        fmt::format("BTF '{}': resolution must be in [1, 4096] and view/light sides in [1, 64] "
                    "(got {}, {}, {})",
                    material_, resolution, view_side, light_side));
  const std::size_t expected =
      static_cast<std::size_t>(texel_count()) * view_count() * light_count() * 3;
  if (rgb_.size() != expected)
    throw ParameterError(fmt::format("BTF '{}': {} values given, {} x {} x {} x 3 = {} expected",
                                     material_, rgb_.size(), texel_count(), view_count(),
                                     light_count(), expected));
  // A NaN or Inf reflectance turns every pixel that touches its texel into NaN, and every
  // compressor's fit of it with it: refused here, where every BTF is built, not per backend.
  if (const auto bad =
          std::find_if(rgb_.begin(), rgb_.end(), [](float x) { return !std::isfinite(x); });
      bad != rgb_.end()) {
    const std::size_t i = static_cast<std::size_t>(bad - rgb_.begin()) / 3;
    const std::size_t m = static_cast<std::size_t>(light_count());
    const std::size_t v = static_cast<std::size_t>(view_count());
    throw ParameterError(
        fmt::format("BTF '{}': a non-finite value ({}) at texel {}, view {}, "
                    "light {}",
                    material_, *bad, i / m / v, i / m % v, i % m));
  }
  // Bitwise comparison: a Lambertian BTF computes the same float for every view, and anything
  // looser would let the skip change a view-dependent image.
  const std::size_t block = static_cast<std::size_t>(light_count()) * 3;
  view_independent_ = skip == ViewSkip::kDetect;
  for (int t = 0; t < texel_count() && view_independent_; ++t) {
    const float* first = rgb_.data() + offset(t, 0, 0);
    for (int v = 1; v < view_count(); ++v) {
      if (std::memcmp(first, rgb_.data() + offset(t, v, 0), block * sizeof(float)) != 0) {
        view_independent_ = false;
        break;
      }
    }
  }
}

int btf_texel_at(int resolution, Vec2 uv) {
  const int x = std::min(static_cast<int>(fract(uv.x) * resolution), resolution - 1);
  const int y = std::min(static_cast<int>(fract(uv.y) * resolution), resolution - 1);
  return y * resolution + x;
}

BtfTexelSamples btf_texel_samples(int resolution, Vec2 uv, TexelFilter filter) {
  BtfTexelSamples s;
  if (filter == TexelFilter::kNearest) {
    s.texel[0] = btf_texel_at(resolution, uv);
    s.weight[0] = 1.0f;
    s.count = 1;
    return s;
  }
  const float fx = fract(uv.x) * resolution - 0.5f, fy = fract(uv.y) * resolution - 0.5f;
  const float x0f = std::floor(fx), y0f = std::floor(fy);
  const float tx = fx - x0f, ty = fy - y0f;
  const int x0 = wrap(static_cast<int>(x0f), resolution), x1 = wrap(x0 + 1, resolution);
  const int y0 = wrap(static_cast<int>(y0f), resolution), y1 = wrap(y0 + 1, resolution);
  s.texel = {y0 * resolution + x0, y0 * resolution + x1, y1 * resolution + x0,
             y1 * resolution + x1};
  s.weight = {(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty};
  s.count = 4;
  return s;
}

int Btf::texel_at(Vec2 uv) const {
  return btf_texel_at(resolution_, uv);
}

BtfTexelSamples Btf::texel_samples(Vec2 uv, TexelFilter filter) const {
  return btf_texel_samples(resolution_, uv, filter);
}

BtfViewSamples Btf::view_samples(Vec3 view_local) const {
  if (!view_independent_) return btf_view_samples(view_side_, view_local);
  BtfViewSamples s;
  s.weight = {1.0f, 0.0f, 0.0f, 0.0f};
  return s;
}

Rgb Btf::eval(Vec2 uv, Vec3 view_local, int light, TexelFilter filter) const {
  PRT_CHECK(light >= 0 && light < light_count(), "light {} out of range", light);
  const BtfTexelSamples ts = texel_samples(uv, filter);
  const BtfViewSamples vs = view_samples(view_local);
  Rgb sum(0.0f);
  for (int t = 0; t < ts.count; ++t)
    for (int k = 0; k < 4; ++k) {
      const float w = ts.weight[t] * vs.weight[k];
      if (w != 0.0f) sum += w * value(ts.texel[t], vs.view[k], light);
    }
  return sum;
}

void Btf::eval_lights(Vec2 uv, Vec3 view_local, std::span<Rgb> out, TexelFilter filter) const {
  PRT_CHECK(out.size() == static_cast<std::size_t>(light_count()), "need {} outputs, got {}",
            light_count(), out.size());
  const BtfTexelSamples ts = texel_samples(uv, filter);
  const BtfViewSamples vs = view_samples(view_local);
  std::fill(out.begin(), out.end(), Rgb(0.0f));
  for (int t = 0; t < ts.count; ++t) {
    for (int k = 0; k < 4; ++k) {
      const float w = ts.weight[t] * vs.weight[k];
      if (w == 0.0f) continue;
      const float* p = rgb_.data() + offset(ts.texel[t], vs.view[k], 0);
      for (int j = 0; j < light_count(); ++j)
        out[j] += w * Rgb(p[3 * j], p[3 * j + 1], p[3 * j + 2]);
    }
  }
}

Rgb Btf::shade(Vec2 uv, Vec3 view_local, std::span<const Rgb> local_radiance,
               TexelFilter filter) const {
  PRT_CHECK(local_radiance.size() == static_cast<std::size_t>(light_count()),
            "need {} local radiance values, got {}", light_count(), local_radiance.size());
  const BtfTexelSamples ts = texel_samples(uv, filter);
  const BtfViewSamples vs = view_samples(view_local);
  Rgb sum(0.0f);
  for (int t = 0; t < ts.count; ++t) {
    for (int k = 0; k < 4; ++k) {
      const float w = ts.weight[t] * vs.weight[k];
      if (w == 0.0f) continue;
      const float* p = rgb_.data() + offset(ts.texel[t], vs.view[k], 0);
      Rgb dot(0.0f);
      for (int j = 0; j < light_count(); ++j)
        dot += Rgb(p[3 * j], p[3 * j + 1], p[3 * j + 2]) * local_radiance[j];
      sum += w * dot;
    }
  }
  return sum;
}

// --- statistics -----------------------------------------------------------------------------

BtfStats btf_stats(const Btf& btf) {
  BtfStats s;
  const HemisphereGrid lights(btf.light_side());
  const std::vector<double> projected = HemisphereGrid(btf.view_side()).projected_solid_angles();
  const std::vector<double> light_projected = lights.projected_solid_angles();
  const int m = btf.light_count();
  std::vector<Vec3d> albedo(m, Vec3d(0.0));
  Vec3d lo(std::numeric_limits<double>::infinity()), hi(-lo), sum(0.0);
  for (int t = 0; t < btf.texel_count(); ++t) {
    for (int v = 0; v < btf.view_count(); ++v) {
      const double w = projected[v];
      const auto vec = btf.light_vector(t, v);
      for (int j = 0; j < m; ++j) {
        for (int c = 0; c < 3; ++c) {
          const double x = vec[3 * j + c];
          if (!std::isfinite(x)) {
            ++s.non_finite;
            continue;
          }
          lo[c] = std::min(lo[c], x);
          hi[c] = std::max(hi[c], x);
          sum[c] += x;
          albedo[j][c] += x * w;
        }
      }
    }
  }
  const double n = static_cast<double>(btf.value_count()) / 3.0;
  s.min = Rgb(lo);
  s.max = Rgb(hi);
  s.mean = Rgb(sum / n);
  s.albedo.resize(m);
  Vec3d amean(0.0), amax(0.0);
  for (int j = 0; j < m; ++j) {
    // The stored values carry the cell-mean cosine of light cell j (see btf.h), not cos(theta_j).
    const double mean_cos = light_projected[j] / lights.cell_solid_angle();
    const Vec3d a = albedo[j] / (btf.texel_count() * mean_cos);
    s.albedo[j] = Rgb(a);
    amean += a / static_cast<double>(m);
    amax = glm::max(amax, a);
  }
  s.albedo_mean = Rgb(amean);
  s.albedo_max = Rgb(amax);
  return s;
}

Btf without_view_skip(const Btf& btf) {
  return Btf(btf.material(), btf.resolution(), btf.view_side(), btf.light_side(),
             std::vector<float>(btf.data().begin(), btf.data().end()), btf.parameters(),
             ViewSkip::kNever);
}

// --- archive --------------------------------------------------------------------------------

namespace {

std::vector<float> direction_table(int side) {
  const HemisphereGrid grid(side);
  std::vector<float> out;
  out.reserve(static_cast<std::size_t>(grid.cell_count()) * 3);
  for (const Vec3d& d : grid.directions())
    out.insert(out.end(), {float(d.x), float(d.y), float(d.z)});
  return out;
}

}  // namespace

ArchiveWriter save_btf(Btf btf) {
  ArchiveWriter w(kBtfArchiveKind, kBtfArchiveVersion);
  w.add_meta("material", btf.material_);
  w.add_meta("resolution", btf.resolution_);
  w.add_meta("view_side", btf.view_side_);
  w.add_meta("light_side", btf.light_side_);
  w.add_meta("parameters", btf.parameters_);
  w.add_meta("layout", "rgb[((texel * V + view) * M + light) * 3 + channel], texel = y * U + x");
  w.add_meta("units",
             "exitant radiance per unit irradiance from the light direction, cosine included");
  w.add_meta("view_independent", btf.view_independent_);
  w.add_section("rgb", std::move(btf.rgb_));
  w.add_section("view_directions", direction_table(btf.view_side_));
  w.add_section("light_directions", direction_table(btf.light_side_));
  return w;
}

Btf load_btf(const ArchiveReader& reader) {
  reader.expect_kind(kBtfArchiveKind, kBtfArchiveVersion);
  const auto material = reader.meta_value<std::string>("material");
  const int u = reader.meta_value<int>("resolution");
  const int vs = reader.meta_value<int>("view_side");
  const int ls = reader.meta_value<int>("light_side");
  if (u < 1 || u > 4096 || vs < 1 || vs > 64 || ls < 1 || ls > 64)
    throw InputError(reader.path(), fmt::format("BTF sizes out of range (resolution {}, view side "
                                                "{}, light side {})",
                                                u, vs, ls));
  nlohmann::json params = nlohmann::json::object();
  if (reader.meta().contains("parameters")) params = reader.meta().at("parameters");
  // The direction tables pin the grid convention: a file written with another map is refused.
  for (const auto& [name, side] :
       {std::pair{"view_directions", vs}, std::pair{"light_directions", ls}}) {
    const auto stored = reader.view<float>(name, static_cast<std::uint64_t>(side) * side * 3);
    const auto expected = direction_table(side);
    for (std::size_t i = 0; i < expected.size(); ++i)
      if (!(std::abs(stored[i] - expected[i]) <= 1e-6f))
        throw InputError(reader.path(), fmt::format("section '{}' does not match the concentric "
                                                    "hemisphere grid of side {}",
                                                    name, side));
  }
  const std::uint64_t count = static_cast<std::uint64_t>(u) * u * vs * vs * ls * ls * 3;
  try {
    return Btf(material, u, vs, ls, reader.section<float>("rgb", count), std::move(params));
  } catch (const ParameterError& e) {
    throw InputError(reader.path(), e.what());
  }
}

void write_btf(const Btf& btf, const std::filesystem::path& file) {
  save_btf(btf).write(file);
}

Btf read_btf(const std::filesystem::path& file) {
  return load_btf(ArchiveReader::open(file, kBtfArchiveKind, kBtfArchiveVersion));
}

}  // namespace prt
