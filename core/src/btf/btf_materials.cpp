#include "prtlab/btf/btf_materials.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "base/integer_hash.h"
#include "prtlab/base/error.h"

namespace prt {

namespace {

constexpr float kPiF = std::numbers::pi_v<float>;

// Smith's Lambda for GGX: the height-correlated masking-shadowing term is 1 / (1 + L(l) + L(v)).
float ggx_lambda(float cos_theta, float alpha2) {
  const float c2 = cos_theta * cos_theta;
  const float tan2 = std::max(0.0f, 1.0f - c2) / c2;
  return 0.5f * (std::sqrt(1.0f + alpha2 * tan2) - 1.0f);
}

float fract(float x) {
  return x - std::floor(x);
}

float smoothstep(float e0, float e1, float x) {
  const float t = std::clamp((x - e0) / (e1 - e0), 0.0f, 1.0f);
  return t * t * (3.0f - 2.0f * t);
}

float lattice_value(int i, int j, int period, std::uint32_t octave) {
  const auto wrap = [period](int k) {
    return static_cast<std::uint32_t>(((k % period) + period) % period);
  };
  return static_cast<float>(hash3(wrap(i), wrap(j), octave) >> 8) / static_cast<float>(1u << 24) *
             2.0f -
         1.0f;
}

// Value noise on a lattice of `period` cells per tile side, periodic with period 1, quintic
// interpolation (C2, so the normals from the height lattice are smooth).
float periodic_noise(float x, float y, int period, std::uint32_t octave) {
  const float fx = x * period, fy = y * period;
  const int i = static_cast<int>(std::floor(fx)), j = static_cast<int>(std::floor(fy));
  const float tx = fx - i, ty = fy - j;
  const auto q = [](float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); };
  const float sx = q(tx), sy = q(ty);
  const float v00 = lattice_value(i, j, period, octave),
              v10 = lattice_value(i + 1, j, period, octave);
  const float v01 = lattice_value(i, j + 1, period, octave);
  const float v11 = lattice_value(i + 1, j + 1, period, octave);
  return (v00 * (1 - sx) + v10 * sx) * (1 - sy) + (v01 * (1 - sx) + v11 * sx) * sy;
}

LocalBrdf brdf(Rgb kd, Rgb ks, float alpha) {
  return LocalBrdf{kd, ks, alpha};
}

// --- the named materials ------------------------------------------------------------------

MesoStructure make_lambert() {
  MesoStructure m;
  m.name = "lambert";
  m.positions = {{0.f, 0.f, 0.f}, {1.f, 0.f, 0.f}, {1.f, 1.f, 0.f}, {0.f, 1.f, 0.f}};
  m.indices = {0, 1, 2, 0, 2, 3};
  m.triangle_brdf = {0, 0};
  m.brdfs = {brdf(Rgb(0.8f), Rgb(0.0f), 1.0f)};
  m.max_height = 0.0f;
  m.parameters = {{"albedo", 0.8}};
  return m;
}

// Suykens et al. 2003: "a height field created from a smoothed checker pattern. The pink,
// raised areas have a more specular BRDF than the blue, lower parts."
MesoStructure make_checker(int grid) {
  constexpr int kChecks = 4;          // per tile side (even, so the pattern tiles)
  constexpr float kHeight = 0.06f;    // of the raised squares, in tile units
  constexpr float kSharpness = 3.0f;  // plateau where |sin sin| > 1/kSharpness
  const auto height = [](float x, float y) {
    const float s = std::sin(kPiF * kChecks * x) * std::sin(kPiF * kChecks * y);
    return kHeight * (0.5f + 0.5f * std::clamp(kSharpness * s, -1.0f, 1.0f));
  };
  // Classified at the triangle's centroid by the analytic pattern, not by its (lattice) height,
  // so the material boundary is unbiased by the lattice.
  const auto which = [](float x, float y, float) {
    return std::sin(kPiF * kChecks * x) * std::sin(kPiF * kChecks * y) > 0.0f ? 1 : 0;
  };
  MesoStructure m = height_field_structure(
      "checker", grid, height, which,
      {brdf({0.10f, 0.16f, 0.45f}, Rgb(0.06f), 0.45f),    // blue base, rough
       brdf({0.55f, 0.22f, 0.32f}, Rgb(0.35f), 0.12f)});  // pink raised squares, glossy
  m.parameters = {{"checks", kChecks}, {"height", kHeight}, {"sharpness", kSharpness}};
  return m;
}

MesoStructure make_bumps(int grid) {
  constexpr int kBumps = 3;         // per tile side
  constexpr float kRadius = 0.13f;  // footprint radius
  constexpr float kHeight = 0.09f;  // cap height
  // Spherical cap of footprint radius R and height H: sphere radius (R^2 + H^2) / 2H.
  constexpr float kSphere = (kRadius * kRadius + kHeight * kHeight) / (2.0f * kHeight);
  const auto height = [](float x, float y) {
    const float dx = fract(x * kBumps) - 0.5f, dy = fract(y * kBumps) - 0.5f;
    const float r2 = (dx * dx + dy * dy) / (kBumps * kBumps);
    if (r2 >= kRadius * kRadius) return 0.0f;
    return std::max(0.0f, std::sqrt(kSphere * kSphere - r2) - (kSphere - kHeight));
  };
  const auto which = [height](float x, float y, float) { return height(x, y) > 0.0f ? 1 : 0; };
  MesoStructure m = height_field_structure(
      "bumps", grid, height, which,
      {brdf({0.30f, 0.38f, 0.32f}, Rgb(0.02f), 0.6f),     // matte grey-green base
       brdf({0.70f, 0.34f, 0.12f}, Rgb(0.15f), 0.25f)});  // orange bumps, semi-gloss
  m.parameters = {{"bumps", kBumps}, {"radius", kRadius}, {"height", kHeight}};
  return m;
}

// Suykens et al. 2003: "concentric gold-like rings laid out on a blue, glossy base plane".
MesoStructure make_rings(int grid) {
  static constexpr float kRadii[] = {0.10f, 0.22f, 0.34f};
  constexpr float kHalfWidth = 0.04f;  // of a ring's elliptical cross-section
  constexpr float kHeight = 0.04f;
  const auto height = [](float x, float y) {
    const float r = std::hypot(x - 0.5f, y - 0.5f);
    float z = 0.0f;
    for (const float rk : kRadii) {
      const float d = (r - rk) / kHalfWidth;
      if (std::abs(d) < 1.0f) z = std::max(z, kHeight * std::sqrt(1.0f - d * d));
    }
    return z;
  };
  const auto which = [height](float x, float y, float) { return height(x, y) > 0.0f ? 1 : 0; };
  MesoStructure m = height_field_structure(
      "rings", grid, height, which,
      {brdf({0.04f, 0.08f, 0.30f}, Rgb(0.30f), 0.08f),               // glossy blue base
       brdf({0.30f, 0.20f, 0.04f}, {0.60f, 0.48f, 0.20f}, 0.18f)});  // gold rings
  m.parameters = {{"radii", {kRadii[0], kRadii[1], kRadii[2]}},
                  {"half_width", kHalfWidth},
                  {"height", kHeight}};
  return m;
}

// Plain weave: warp k (along x, centred at y = (k + 1/2) / n) passes over weft m (along y) where
// k + m is even. Each thread's centre line undulates with amplitude A along its length; its
// cross-section is a half ellipse of half-width w and height T, with a faint twist of fibres.
MesoStructure make_weave(int grid) {
  constexpr int kThreads = 4;          // per tile side and direction (even, so the pattern tiles)
  constexpr float kHalfWidth = 0.42f;  // of a thread, in thread spacings
  constexpr float kAmplitude = 0.018f;
  constexpr float kThickness = 0.035f;
  constexpr float kTwist = 0.0025f;
  // Height of one thread family at (along, across) in thread units; `phase` is 0 for the warp.
  const auto thread = [](float along, float across, float phase) {
    const float k = std::floor(across);
    const float d = (across - k - 0.5f) / kHalfWidth;
    if (std::abs(d) >= 1.0f) return 0.0f;
    const float centre = kAmplitude * (1.0f + std::cos(kPiF * (along - 0.5f + k) + phase));
    const float fibre = kTwist * std::sin(2.0f * kPiF * (3.0f * along + 1.5f * (across - k)));
    return 0.004f + centre + kThickness * std::sqrt(1.0f - d * d) + fibre * std::sqrt(1.0f - d * d);
  };
  const auto warp = [thread](float x, float y) { return thread(x * kThreads, y * kThreads, 0.0f); };
  const auto weft = [thread](float x, float y) { return thread(y * kThreads, x * kThreads, kPiF); };
  const auto height = [warp, weft](float x, float y) { return std::max(warp(x, y), weft(x, y)); };
  const auto which = [warp, weft](float x, float y, float) {
    const float a = warp(x, y), b = weft(x, y);
    if (a == 0.0f && b == 0.0f) return 0;
    return a >= b ? 1 : 2;
  };
  MesoStructure m = height_field_structure(
      "weave", grid, height, which,
      {brdf({0.05f, 0.04f, 0.04f}, Rgb(0.0f), 1.0f),      // dark base between the threads
       brdf({0.60f, 0.10f, 0.08f}, Rgb(0.08f), 0.35f),    // red warp
       brdf({0.80f, 0.74f, 0.58f}, Rgb(0.08f), 0.35f)});  // cream weft
  m.parameters = {{"threads", kThreads},
                  {"half_width", kHalfWidth},
                  {"amplitude", kAmplitude},
                  {"thickness", kThickness}};
  return m;
}

MesoStructure make_stucco(int grid) {
  constexpr float kHeight = 0.035f;
  const auto height = [](float x, float y) {
    float f = 0.0f, amp = 0.5f;
    int period = 4;
    for (std::uint32_t o = 0; o < 5; ++o, amp *= 0.5f, period *= 2)
      f += amp * periodic_noise(x, y, period, o);
    // Plaster daubs: flat-topped blobs with soft edges, plus fine grain everywhere.
    const float blobs = smoothstep(-0.15f, 0.35f, f);
    return kHeight * (0.15f + 0.75f * blobs + 0.10f * (0.5f + 0.5f * periodic_noise(x, y, 64, 9)));
  };
  const auto which = [](float, float, float) { return 0; };
  MesoStructure m = height_field_structure("stucco", grid, height, which,
                                           {brdf({0.78f, 0.74f, 0.66f}, Rgb(0.04f), 0.5f)});
  m.parameters = {{"height", kHeight}, {"octaves", 5}};
  return m;
}

// Periodic cellular (Worley) noise on `cells` x `cells` jittered feature points per tile: the
// distances, in tile units, from (x, y) to the nearest and second-nearest feature point over the
// periodic tiling, and the nearest point's cell id. The 5 x 5 neighbourhood makes both exact for
// jitter within a cell.
struct CellDistances {
  float d1 = 1e9f, d2 = 1e9f;
  std::uint32_t cell = 0;
};

CellDistances periodic_cells(float x, float y, int cells, std::uint32_t seed) {
  const float fx = x * cells, fy = y * cells;
  const int ci = static_cast<int>(std::floor(fx)), cj = static_cast<int>(std::floor(fy));
  const auto wrap = [cells](int k) {
    return static_cast<std::uint32_t>(((k % cells) + cells) % cells);
  };
  const auto unit = [](std::uint32_t h) {
    return static_cast<float>(h >> 8) / static_cast<float>(1u << 24);
  };
  CellDistances r;
  for (int dj = -2; dj <= 2; ++dj)
    for (int di = -2; di <= 2; ++di) {
      const std::uint32_t wi = wrap(ci + di), wj = wrap(cj + dj);
      const float px = ci + di + 0.1f + 0.8f * unit(hash3(wi, wj, seed));
      const float py = cj + dj + 0.1f + 0.8f * unit(hash3(wi, wj, seed + 1));
      const float d = std::hypot(px - fx, py - fy) / cells;
      if (d < r.d1) {
        r.d2 = r.d1;
        r.d1 = d;
        r.cell = wj * static_cast<std::uint32_t>(cells) + wi;
      } else if (d < r.d2) {
        r.d2 = d;
      }
    }
  return r;
}

// A measured-looking stone (after the rough stone and plaster samples of the Bonn BTF database):
// a conglomerate of grains (cellular noise, its domain warped by noise so the borders meander),
// each grain one mineral, separated by narrow dark crevices, the grain tops worn into flat
// semi-glossy plateaus, multi-octave noise relief and fine grain everywhere. The relief is about
// three times stucco's and the crevice walls are steeper than 45 degrees, so masking and
// self-shadowing dominate at grazing angles. Every period divides the tile, so the height field
// is periodic with period 1; the finest octave (32 per tile) keeps 4 lattice cells per noise
// cell at the smallest default geometry grid (128).
struct StoneFields {
  float border;        ///< distance to the nearest grain border, tile units (about 0 .. 0.1)
  float relief;        ///< 0 .. 1, multi-octave noise
  float grain;         ///< 0 .. 1, fine roughness
  std::uint32_t cell;  ///< the grain
};

constexpr int kStoneGrains = 5;             // per tile side
constexpr float kStoneHeight = 0.10f;       // of the grain tops above the crevice floors
constexpr float kStoneCrackWidth = 0.022f;  // tile units from the border to the grain's flank
constexpr float kStoneShoulder = 0.06f;     // tile units from the border to the plateau

StoneFields stone_fields(float x, float y) {
  StoneFields s;
  const float wx = x + 0.05f * periodic_noise(x, y, 4, 30) + 0.02f * periodic_noise(x, y, 8, 32);
  const float wy = y + 0.05f * periodic_noise(x, y, 4, 31) + 0.02f * periodic_noise(x, y, 8, 33);
  const CellDistances c = periodic_cells(wx, wy, kStoneGrains, 34);
  s.border = 0.5f * (c.d2 - c.d1);
  s.cell = c.cell;
  float f = 0.0f, amp = 0.5f;
  int period = 4;
  for (std::uint32_t o = 0; o < 4; ++o, amp *= 0.5f, period *= 2)
    f += amp * periodic_noise(x, y, period, 20 + o);
  s.relief = std::clamp(0.5f + 0.6f * f, 0.0f, 1.0f);
  s.grain =
      0.5f + 0.5f * (0.6f * periodic_noise(x, y, 32, 24) + 0.4f * periodic_noise(x, y, 16, 25));
  return s;
}

// 0 at the grain border, 1 on the plateau.
float stone_rise(const StoneFields& s) {
  return smoothstep(0.0f, kStoneCrackWidth, s.border) * 0.55f +
         smoothstep(kStoneCrackWidth, kStoneShoulder, s.border) * 0.45f;
}

float stone_height(float x, float y) {
  const StoneFields s = stone_fields(x, y);
  return kStoneHeight * (0.03f + stone_rise(s) * (0.62f + 0.25f * s.relief) + 0.10f * s.grain);
}

MesoStructure make_stone(int grid) {
  const auto which = [](float x, float y, float) {
    const StoneFields s = stone_fields(x, y);
    if (s.border < 0.5f * kStoneCrackWidth) return 0;             // crevice floor and walls
    if (s.border > kStoneShoulder && s.relief > 0.45f) return 4;  // worn plateau
    const std::uint32_t mineral = hash3(s.cell, 7, 35) % 5;       // 2 : 2 : 1
    return mineral < 2 ? 1 : mineral < 4 ? 2 : 3;
  };
  MesoStructure m = height_field_structure(
      "stone", grid, stone_height, which,
      {brdf({0.06f, 0.05f, 0.045f}, Rgb(0.01f), 0.8f),    // dark rough crevices
       brdf({0.42f, 0.36f, 0.28f}, Rgb(0.04f), 0.5f),     // warm ochre-grey grains
       brdf({0.28f, 0.30f, 0.33f}, Rgb(0.04f), 0.5f),     // cool blue-grey grains
       brdf({0.46f, 0.24f, 0.14f}, Rgb(0.05f), 0.4f),     // rust grains
       brdf({0.60f, 0.56f, 0.50f}, Rgb(0.16f), 0.18f)});  // polished plateaus, semi-glossy
  m.parameters = {{"grains", kStoneGrains},
                  {"height", kStoneHeight},
                  {"crack_width", kStoneCrackWidth},
                  {"shoulder", kStoneShoulder},
                  {"octaves", 4}};
  return m;
}

}  // namespace

Rgb LocalBrdf::eval(const Vec3& n, const Vec3& l, const Vec3& v) const {
  const float nl = glm::dot(n, l), nv = glm::dot(n, v);
  if (!(nl > 0.0f) || !(nv > 0.0f)) return Rgb(0.0f);
  Rgb f = diffuse * (1.0f / kPiF);
  if (specular.x > 0.0f || specular.y > 0.0f || specular.z > 0.0f) {
    const Vec3 h = glm::normalize(l + v);
    const float nh = glm::dot(n, h);
    const float a2 = roughness * roughness;
    const float den = nh * nh * (a2 - 1.0f) + 1.0f;
    const float d = a2 / (kPiF * den * den);
    const float g = 1.0f / (1.0f + ggx_lambda(nl, a2) + ggx_lambda(nv, a2));
    f += specular * (d * g / (4.0f * nl * nv));
  }
  return f;
}

void MesoStructure::validate() const {
  const auto fail = [this](const std::string& what) {
    throw ParameterError(fmt::format("meso-structure '{}': {}", name, what));
  };
  if (indices.empty() || indices.size() % 3 != 0) fail("needs a non-empty list of triangles");
  if (triangle_brdf.size() != triangle_count()) fail("needs one BRDF index per triangle");
  if (!normals.empty() && normals.size() != positions.size()) fail("needs one normal per vertex");
  if (brdfs.empty() || brdfs.size() > 256) fail("needs 1..256 BRDFs");
  if (!(max_height >= 0.0f)) fail("max_height must be >= 0");
  for (const std::uint32_t i : indices)
    if (i >= positions.size()) fail(fmt::format("vertex index {} out of range", i));
  for (const Vec3& p : positions) {
    if (!(p.x >= 0.0f && p.x <= 1.0f && p.y >= 0.0f && p.y <= 1.0f && p.z >= 0.0f &&
          p.z <= max_height))
      fail(fmt::format("vertex ({}, {}, {}) outside the tile [0,1]^2 x [0, {}]", p.x, p.y, p.z,
                       max_height));
  }
  for (const std::uint8_t b : triangle_brdf)
    if (b >= brdfs.size()) fail(fmt::format("BRDF index {} out of range", b));
  for (const LocalBrdf& b : brdfs)
    if (!(b.roughness > 0.0f)) fail("GGX roughness must be > 0");
}

MesoStructure height_field_structure(std::string name, int grid,
                                     const std::function<float(float x, float y)>& height,
                                     const std::function<int(float x, float y, float z)>& brdf_at,
                                     std::vector<LocalBrdf> brdfs) {
  if (grid < 1 || grid > 4096)
    throw ParameterError(fmt::format("height-field grid must be in [1, 4096], got {}", grid));
  MesoStructure m;
  m.name = std::move(name);
  m.brdfs = std::move(brdfs);
  const int g = grid, side = g + 1;
  // Heights on the periodic g x g lattice; the (g+1)-th row and column repeat the first, so the
  // tile's opposite edges match exactly.
  std::vector<float> h(static_cast<std::size_t>(g) * g);
  for (int j = 0; j < g; ++j)
    for (int i = 0; i < g; ++i)
      h[static_cast<std::size_t>(j) * g + i] =
          std::max(0.0f, height(static_cast<float>(i) / g, static_cast<float>(j) / g));
  const auto at = [&](int i, int j) {
    return h[static_cast<std::size_t>(((j % g) + g) % g) * g + ((i % g) + g) % g];
  };
  m.positions.reserve(static_cast<std::size_t>(side) * side);
  m.normals.reserve(m.positions.capacity());
  for (int j = 0; j < side; ++j) {
    for (int i = 0; i < side; ++i) {
      const float z = at(i, j);
      m.max_height = std::max(m.max_height, z);
      m.positions.emplace_back(static_cast<float>(i) / g, static_cast<float>(j) / g, z);
      const float dzdx = (at(i + 1, j) - at(i - 1, j)) * 0.5f * g;
      const float dzdy = (at(i, j + 1) - at(i, j - 1)) * 0.5f * g;
      m.normals.push_back(glm::normalize(Vec3(-dzdx, -dzdy, 1.0f)));
    }
  }
  m.indices.reserve(static_cast<std::size_t>(g) * g * 6);
  m.triangle_brdf.reserve(static_cast<std::size_t>(g) * g * 2);
  const auto add = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    m.indices.insert(m.indices.end(), {a, b, c});
    const Vec3 centroid = (m.positions[a] + m.positions[b] + m.positions[c]) / 3.0f;
    const int id = brdf_at(centroid.x, centroid.y, centroid.z);
    if (id < 0 || static_cast<std::size_t>(id) >= m.brdfs.size())
      throw ParameterError(
          fmt::format("meso-structure '{}': BRDF index {} out of range", m.name, id));
    m.triangle_brdf.push_back(static_cast<std::uint8_t>(id));
  };
  for (int j = 0; j < g; ++j) {
    for (int i = 0; i < g; ++i) {
      const auto v00 = static_cast<std::uint32_t>(j * side + i);
      const std::uint32_t v10 = v00 + 1, v01 = v00 + side, v11 = v01 + 1;
      add(v00, v10, v11);  // counter-clockwise seen from above
      add(v00, v11, v01);
    }
  }
  m.parameters = nlohmann::json::object();
  m.validate();
  return m;
}

MesoStructure box_bump_structure(float width, float height, const LocalBrdf& base,
                                 const LocalBrdf& box) {
  if (!(width > 0.0f && width < 1.0f) || !(height > 0.0f))
    throw ParameterError(
        fmt::format("box bump: need 0 < width < 1 and height > 0 (got {}, {})", width, height));
  MesoStructure m;
  m.name = "box";
  m.brdfs = {base, box};
  m.max_height = height;
  const float lo = 0.5f - 0.5f * width, hi = 0.5f + 0.5f * width;
  const auto quad = [&](Vec3 a, Vec3 b, Vec3 c, Vec3 d, std::uint8_t id) {
    const auto k = static_cast<std::uint32_t>(m.positions.size());
    m.positions.insert(m.positions.end(), {a, b, c, d});
    m.indices.insert(m.indices.end(), {k, k + 1, k + 2, k, k + 2, k + 3});
    m.triangle_brdf.insert(m.triangle_brdf.end(), {id, id});
  };
  const float z = height;
  quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, 0);          // base (also under the box)
  quad({lo, lo, z}, {hi, lo, z}, {hi, hi, z}, {lo, hi, z}, 1);  // top
  quad({lo, lo, 0}, {hi, lo, 0}, {hi, lo, z}, {lo, lo, z}, 1);  // -y wall
  quad({hi, lo, 0}, {hi, hi, 0}, {hi, hi, z}, {hi, lo, z}, 1);  // +x wall
  quad({hi, hi, 0}, {lo, hi, 0}, {lo, hi, z}, {hi, hi, z}, 1);  // +y wall
  quad({lo, hi, 0}, {lo, lo, 0}, {lo, lo, z}, {lo, hi, z}, 1);  // -x wall
  m.parameters = {{"width", width}, {"height", height}};
  m.validate();
  return m;
}

namespace {

struct MaterialEntry {
  const char* name;
  const char* description;
  MesoStructure (*make)(int grid);
};

// The one list of built-in materials: adding one is adding its maker and a line here.
const std::vector<MaterialEntry>& material_table() {
  static const std::vector<MaterialEntry> table = {
      {"lambert", "flat Lambertian plane, albedo 0.8", [](int) { return make_lambert(); }},
      {"checker", "smoothed 4x4 checker: glossy pink raised squares over a rough blue base",
       make_checker},
      {"bumps", "3x3 spherical-cap bumps (orange, semi-gloss) on a matte grey-green base",
       make_bumps},
      {"rings", "three concentric gold rings on a glossy blue base", make_rings},
      {"weave", "plain weave of red warp and cream weft threads over a dark base", make_weave},
      {"stucco", "periodic fractal-noise plaster, matte", make_stucco},
      {"stone", "rough stone: semi-glossy worn plateaus, deep dark crevices, mineral colours",
       make_stone},
  };
  return table;
}

}  // namespace

const std::vector<std::string>& btf_material_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const auto& e : material_table()) n.emplace_back(e.name);
    return n;
  }();
  return names;
}

std::string btf_material_description(std::string_view name) {
  for (const auto& e : material_table())
    if (name == e.name) return e.description;
  return {};
}

bool is_btf_material(std::string_view name) {
  const auto& n = btf_material_names();
  return std::find(n.begin(), n.end(), name) != n.end();
}

MesoStructure make_btf_material(std::string_view name, int grid) {
  if (grid < 8 || grid > 4096)
    throw ParameterError(fmt::format("BTF geometry grid must be in [8, 4096], got {}", grid));
  for (const auto& e : material_table())
    if (name == e.name) return e.make(grid);
  std::string valid;
  for (const auto& n : btf_material_names()) valid += (valid.empty() ? "" : ", ") + n;
  throw ParameterError(
      fmt::format("unknown BTF material '{}' (valid: {})", std::string(name), valid));
}

}  // namespace prt
