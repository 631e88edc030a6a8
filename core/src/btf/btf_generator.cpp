#include "prtlab/btf/btf_generator.h"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>
#include <optional>
#include <string>

#include "geometry/embree_triangle_scene.h"
#include "base/integer_hash.h"
#include "prtlab/base/error.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/sphere/local_frame.h"
#include "prtlab/base/log.h"
#include "prtlab/base/progress.h"

namespace prt {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
// Origin offset of secondary rays along the geometric normal, in tile units (the tile is 1 wide,
// structures are a few hundredths high, lattice cells >= 1/4096).
constexpr float kRayOffset = 1e-4f;
// The slab the structure lives in ends this far above max_height: rays start (views) or end
// (shadows) there.
constexpr float kSlabMargin = 1e-3f;
// A ray crosses at most this many tile sides: even a shadow ray at 1 degree above the horizon
// rises out of a 0.1-high structure within about 6 tiles.
constexpr int kMaxSegments = 4096;

float unit_float(std::uint32_t v) {
  return static_cast<float>(v >> 8) * (1.0f / 16777216.0f);
}

float radical_inverse2(std::uint32_t i) {
  i = (i << 16) | (i >> 16);
  i = ((i & 0x00ff00ffu) << 8) | ((i & 0xff00ff00u) >> 8);
  i = ((i & 0x0f0f0f0fu) << 4) | ((i & 0xf0f0f0f0u) >> 4);
  i = ((i & 0x33333333u) << 2) | ((i & 0xccccccccu) >> 2);
  i = ((i & 0x55555555u) << 1) | ((i & 0xaaaaaaaau) >> 1);
  return unit_float(i);
}

}  // namespace

// --- BtfParams ------------------------------------------------------------------------------

void BtfParams::validate() const {
  const auto check = [](bool ok, const char* name, int value, const char* range) {
    if (!ok)
      throw ParameterError(
          fmt::format("BTF parameter {} = {} out of range {}", name, value, range));
  };
  check(resolution >= 1 && resolution <= 1024, "resolution", resolution, "[1, 1024]");
  check(view_side >= 1 && view_side <= 64, "view_side", view_side, "[1, 64]");
  check(light_side >= 1 && light_side <= 64, "light_side", light_side, "[1, 64]");
  check(supersampling >= 1 && supersampling <= 8, "supersampling", supersampling, "[1, 8]");
  check(interreflection_samples >= 0 && interreflection_samples <= 1024, "interreflection_samples",
        interreflection_samples, "[0, 1024]");
  check(geometry_grid == 0 || (geometry_grid >= 8 && geometry_grid <= 4096), "geometry_grid",
        geometry_grid, "0 or [8, 4096]");
}

int BtfParams::effective_geometry_grid() const {
  return geometry_grid > 0 ? geometry_grid : std::clamp(4 * resolution, 128, 1024);
}

nlohmann::json BtfParams::to_json() const {
  return {{"resolution", resolution},
          {"view_side", view_side},
          {"light_side", light_side},
          {"supersampling", supersampling},
          {"interreflection_samples", interreflection_samples},
          {"geometry_grid", effective_geometry_grid()},
          {"seed", seed}};
}

// --- MesoTracer -----------------------------------------------------------------------------

struct MesoTracer::Impl {
  MesoStructure meso;
  std::vector<Vec3> triangle_normal;  // unit geometric normals (winding as given)
  float ceiling = 0.0f;
  std::optional<EmbreeTriangleScene> embree;
  RTCScene scene = nullptr;  // embree->scene()

  // One segment inside the tile: Embree's first hit in [0, tfar] (or any hit for occlusion).
  bool segment(const Vec3& o, const Vec3& d, float tfar, bool any, RTCRayHit& rh) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    rh = RTCRayHit{};
    rh.ray.org_x = o.x;
    rh.ray.org_y = o.y;
    rh.ray.org_z = o.z;
    rh.ray.dir_x = d.x;
    rh.ray.dir_y = d.y;
    rh.ray.dir_z = d.z;
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = tfar;
    rh.ray.mask = ~0u;
    rh.ray.flags = 0;
    rh.ray.time = 0.0f;
    if (any) {
      rtcOccluded1(scene, &context, &rh.ray);
      return rh.ray.tfar < 0.0f;
    }
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene, &context, &rh);
    return rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
  }

  // Walks the ray through the periodic tiling: a ray that leaves the tile through a side
  // re-enters through the opposite one, until it hits, rises out of the slab or falls below it.
  Hit walk(Vec3 o, const Vec3& d, bool any) const {
    Hit hit;
    o.x -= std::floor(o.x);
    o.y -= std::floor(o.y);
    if (d.z >= 0.0f && o.z >= ceiling) return hit;
    for (int seg = 0; seg < kMaxSegments; ++seg) {
      const float tx = d.x > 0.0f ? (1.0f - o.x) / d.x : d.x < 0.0f ? -o.x / d.x : kInf;
      const float ty = d.y > 0.0f ? (1.0f - o.y) / d.y : d.y < 0.0f ? -o.y / d.y : kInf;
      const float t_top = d.z > 0.0f ? (ceiling - o.z) / d.z : kInf;
      const float t_side = std::min(tx, ty);
      const float tfar = std::min(t_side, t_top);
      RTCRayHit rh;
      // A hair beyond the boundary, so a triangle edge lying on it cannot slip between segments.
      if (segment(o, d, tfar * (1.0f + 1e-5f) + 1e-7f, any, rh)) {
        hit.found = true;
        if (any) return hit;
        fill(hit, o, d, rh);
        return hit;
      }
      if (t_top <= t_side || !(t_side < kInf)) return hit;
      o += d * t_side;
      if (tx <= ty) o.x = d.x > 0.0f ? 0.0f : 1.0f;
      if (ty <= tx) o.y = d.y > 0.0f ? 0.0f : 1.0f;
      o.x = std::clamp(o.x, 0.0f, 1.0f);
      o.y = std::clamp(o.y, 0.0f, 1.0f);
      if (o.z < -1.0f) return hit;  // fell through a hole in the base: no surface
    }
    return hit;
  }

  void fill(Hit& hit, const Vec3& o, const Vec3& d, const RTCRayHit& rh) const {
    const std::uint32_t tri = rh.hit.primID;
    Vec3 p = o + d * rh.ray.tfar;
    p.x -= std::floor(p.x);
    p.y -= std::floor(p.y);
    Vec3 ng = triangle_normal[tri];
    if (glm::dot(ng, d) > 0.0f) ng = -ng;
    Vec3 ns = ng;
    if (!meso.normals.empty()) {
      const std::uint32_t* idx = &meso.indices[3 * static_cast<std::size_t>(tri)];
      const float u = rh.hit.u, v = rh.hit.v;
      const Vec3 n = (1.0f - u - v) * meso.normals[idx[0]] + u * meso.normals[idx[1]] +
                     v * meso.normals[idx[2]];
      const float len = glm::length(n);
      if (len > 0.0f) {
        ns = n / len;
        if (glm::dot(ns, ng) <= 0.0f) ns = ng;
      }
    }
    hit.position = p;
    hit.geometric_normal = ng;
    hit.shading_normal = ns;
    hit.brdf = meso.triangle_brdf[tri];
    hit.triangle = tri;
  }
};

MesoTracer::MesoTracer(const MesoStructure& meso) : impl_(std::make_unique<Impl>()) {
  meso.validate();
  Impl& m = *impl_;
  m.meso = meso;
  m.ceiling = meso.max_height + kSlabMargin;
  const std::size_t nt = meso.triangle_count();
  m.triangle_normal.resize(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const Vec3& a = meso.positions[meso.indices[3 * t]];
    const Vec3& b = meso.positions[meso.indices[3 * t + 1]];
    const Vec3& c = meso.positions[meso.indices[3 * t + 2]];
    const Vec3 n = glm::cross(b - a, c - a);
    const float len = glm::length(n);
    m.triangle_normal[t] = len > 0.0f ? n / len : Vec3(0.f, 0.f, 1.f);
  }

  m.embree.emplace(meso.positions, meso.indices);
  m.scene = m.embree->scene();
}

MesoTracer::~MesoTracer() = default;
MesoTracer::MesoTracer(MesoTracer&&) noexcept = default;
MesoTracer& MesoTracer::operator=(MesoTracer&&) noexcept = default;

const MesoStructure& MesoTracer::structure() const {
  return impl_->meso;
}

MesoTracer::Hit MesoTracer::trace(Vec3 origin, Vec3 dir) const {
  return impl_->walk(origin, dir, false);
}

bool MesoTracer::occluded(Vec3 origin, Vec3 dir) const {
  return impl_->walk(origin, dir, true).found;
}

MesoTracer::Hit MesoTracer::visible_point(Vec2 xy, Vec3 e) const {
  PRT_CHECK(e.z > 0.0f, "view direction below the horizon ({}, {}, {})", e.x, e.y, e.z);
  // Start on the slab's ceiling, straight above q along e, and look down along -e.
  const float s = impl_->ceiling / e.z;
  return impl_->walk(Vec3(xy.x + e.x * s, xy.y + e.y * s, impl_->ceiling), -e, false);
}

// --- generation -----------------------------------------------------------------------------

namespace {

struct ShadeContext {
  const MesoTracer& tracer;
  const MesoStructure& meso;
  std::span<const Vec3> lights;
  int ir_samples;
};

// Direct light reflected at a hit towards `to_viewer`, for every light, times `scale`, added.
void add_direct(const ShadeContext& c, const MesoTracer::Hit& h, Vec3 n, const Vec3& to_viewer,
                const Rgb& scale, Rgb* acc) {
  const Vec3& ng = h.geometric_normal;
  if (glm::dot(n, to_viewer) <= 0.0f) n = ng;
  if (glm::dot(n, to_viewer) <= 0.0f) return;
  const LocalBrdf& brdf = c.meso.brdfs[h.brdf];
  const Vec3 origin = h.position + kRayOffset * ng;
  for (std::size_t j = 0; j < c.lights.size(); ++j) {
    const Vec3& l = c.lights[j];
    const float cos_l = glm::dot(n, l);
    if (cos_l <= 0.0f || glm::dot(ng, l) <= 0.0f) continue;
    if (c.tracer.occluded(origin, l)) continue;
    acc[j] += scale * brdf.eval(n, l, to_viewer) * cos_l;
  }
}

// One point q of the reference plane seen from e: masking, shadowing, optional one bounce.
void shade_point(const ShadeContext& c, Vec2 q, const Vec3& e, std::uint32_t seed, Rgb* acc) {
  const MesoTracer::Hit h = c.tracer.visible_point(q, e);
  if (!h.found) return;
  Vec3 n = h.shading_normal;
  const Vec3& ng = h.geometric_normal;
  if (glm::dot(n, e) <= 0.0f) n = ng;
  if (glm::dot(n, e) <= 0.0f) return;
  add_direct(c, h, n, e, Rgb(1.0f), acc);
  if (c.ir_samples == 0) return;

  // One bounce: cosine-weighted directions around n (Hammersley points, randomly rotated per
  // point, so the estimate is f * L_in * pi / K per sample).
  const LocalFrame frame = LocalFrame::from_normal(Vec3d(n));
  const Vec3 t(frame.t), b(frame.b);
  const LocalBrdf& brdf = c.meso.brdfs[h.brdf];
  const Vec3 origin = h.position + kRayOffset * ng;
  const float r1 = unit_float(mix32(seed)), r2 = unit_float(mix32(seed ^ 0x9e3779b9u));
  const float weight = std::numbers::pi_v<float> / static_cast<float>(c.ir_samples);
  for (int k = 0; k < c.ir_samples; ++k) {
    float s1 = (static_cast<float>(k) + 0.5f) / static_cast<float>(c.ir_samples) + r1;
    float s2 = radical_inverse2(static_cast<std::uint32_t>(k)) + r2;
    s1 -= std::floor(s1);
    s2 -= std::floor(s2);
    const float rad = std::sqrt(s1), phi = 2.0f * std::numbers::pi_v<float> * s2;
    const Vec3 w = glm::normalize(rad * std::cos(phi) * t + rad * std::sin(phi) * b +
                                  std::sqrt(std::max(0.0f, 1.0f - s1)) * n);
    if (glm::dot(ng, w) <= 0.0f) continue;
    const Rgb f = brdf.eval(n, w, e);
    if (f == Rgb(0.0f)) continue;
    const MesoTracer::Hit h2 = c.tracer.trace(origin, w);
    if (!h2.found) continue;
    add_direct(c, h2, h2.shading_normal, -w, f * weight, acc);
  }
}

std::vector<Vec3> float_directions(const HemisphereGrid& grid) {
  std::vector<Vec3> out;
  out.reserve(grid.directions().size());
  for (const Vec3d& d : grid.directions()) out.emplace_back(glm::normalize(Vec3(d)));
  return out;
}

}  // namespace

Btf generate_btf(const MesoStructure& meso, const BtfParams& params, bool show_progress) {
  params.validate();
  const MesoTracer tracer(meso);
  const HemisphereGrid view_grid(params.view_side), light_grid(params.light_side);
  const std::vector<Vec3> views = float_directions(view_grid);
  const std::vector<Vec3> lights = float_directions(light_grid);
  const int u = params.resolution, ss = params.supersampling;
  const int nv = view_grid.cell_count(), nl = light_grid.cell_count();
  const std::size_t per_texel = static_cast<std::size_t>(nv) * nl;
  std::vector<float> rgb(static_cast<std::size_t>(u) * u * per_texel * 3);
  const ShadeContext ctx{tracer, tracer.structure(), lights, params.interreflection_samples};
  Progress progress("btf " + meso.name, static_cast<std::int64_t>(u) * u, show_progress);
  const float inv_samples = 1.0f / static_cast<float>(ss * ss);
  // Light-direction quadrature (btf.h "Units"): the response is point-sampled at the cell centre
  // d_j, but the macro cosine is integrated over the cell: each light's value is scaled by
  // (P_j / Omega_j) / cos(theta_j), the cell-mean cosine over the centre's cosine. With L*_j the
  // radiance integrated over cell j, sum_j b_j L*_j is then exact for a flat Lambertian under
  // any light that is constant within cells (the centre cosine alone overestimates the
  // irradiance by about 2 / S^2: 3.1 % at S = 8; docs/image-error.md derives it).
  std::vector<float> cosine_weight(static_cast<std::size_t>(nl));
  {
    const std::vector<double> projected = light_grid.projected_solid_angles();
    for (int j = 0; j < nl; ++j)
      cosine_weight[j] = static_cast<float>(projected[j] / light_grid.cell_solid_angle() /
                                            light_grid.direction(j).z);
  }

  tbb::parallel_for(tbb::blocked_range<int>(0, u * u, 1), [&](const tbb::blocked_range<int>& r) {
    std::vector<Rgb> acc(per_texel);
    for (int texel = r.begin(); texel != r.end(); ++texel) {
      std::fill(acc.begin(), acc.end(), Rgb(0.0f));
      const int x = texel % u, y = texel / u;
      for (int sy = 0; sy < ss; ++sy) {
        for (int sx = 0; sx < ss; ++sx) {
          const Vec2 q((static_cast<float>(x) + (sx + 0.5f) / ss) / static_cast<float>(u),
                       (static_cast<float>(y) + (sy + 0.5f) / ss) / static_cast<float>(u));
          for (int v = 0; v < nv; ++v) {
            const std::uint32_t seed =
                mix32(params.seed ^ mix32(static_cast<std::uint32_t>(texel) * 0x9e3779b1u +
                                          static_cast<std::uint32_t>((sy * ss + sx) * nv + v)));
            shade_point(ctx, q, views[v], seed, acc.data() + static_cast<std::size_t>(v) * nl);
          }
        }
      }
      float* out = rgb.data() + static_cast<std::size_t>(texel) * per_texel * 3;
      for (std::size_t i = 0; i < per_texel; ++i) {
        const float w = inv_samples * cosine_weight[i % static_cast<std::size_t>(nl)];
        out[3 * i + 0] = acc[i].x * w;
        out[3 * i + 1] = acc[i].y * w;
        out[3 * i + 2] = acc[i].z * w;
      }
      progress.advance();
    }
  });
  progress.finish();

  nlohmann::json p = params.to_json();
  p["structure"] = meso.parameters;
  p["triangles"] = meso.triangle_count();
  p["max_height"] = meso.max_height;
  return Btf(meso.name, u, params.view_side, params.light_side, std::move(rgb), std::move(p));
}

Hash128 btf_cache_key(const MesoStructure& meso, const BtfParams& params) {
  Hasher h;
  h.add(kBtfArchiveKind)
      .add(kBtfArchiveVersion)
      .add(kBtfGeneratorVersion)
      .add(kBtfMaterialsVersion)
      .add(meso.name)
      .add(params.resolution)
      .add(params.view_side)
      .add(params.light_side)
      .add(params.supersampling)
      .add(params.interreflection_samples)
      .add(params.effective_geometry_grid())
      .add(params.seed)
      .add(meso.max_height)
      .add_array(meso.positions)
      .add_array(meso.normals)
      .add_array(meso.indices)
      .add_array(meso.triangle_brdf);
  for (const LocalBrdf& b : meso.brdfs) {
    h.add(b.diffuse.x).add(b.diffuse.y).add(b.diffuse.z);
    h.add(b.specular.x).add(b.specular.y).add(b.specular.z).add(b.roughness);
  }
  return h.digest();
}

BtfStageResult generate_btf_cached(std::string_view material, const BtfParams& params,
                                   StageCache& cache, CacheMode mode, bool show_progress) {
  const auto t0 = std::chrono::steady_clock::now();
  params.validate();
  const MesoStructure meso = make_btf_material(material, params.effective_geometry_grid());
  BtfStageResult out;
  out.key = btf_cache_key(meso, params);
  out.cache_file = cache.path_for("btf", out.key);
  bool computed = false;
  out.btf = cache.get_or_compute(
      "btf", out.key,
      [&] {
        computed = true;
        const auto tg = std::chrono::steady_clock::now();
        Btf btf = generate_btf(meso, params, show_progress);
        out.generate_seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - tg).count();
        return save_btf(std::move(btf));
      },
      [](const ArchiveReader& r) { return load_btf(r); }, mode);
  out.cache_hit = !computed;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace prt
