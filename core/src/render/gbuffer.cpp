#include "prtlab/render/gbuffer.h"

#include <embree3/rtcore.h>
#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "geometry/embree_triangle_scene.h"
#include "prtlab/base/error.h"
#include "render/primary_raster.h"

namespace prt {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr int kTile = 16;

void put4(std::vector<float>& a, std::size_t i, const Vec3d& v) {
  a[4 * i + 0] = static_cast<float>(v.x);
  a[4 * i + 1] = static_cast<float>(v.y);
  a[4 * i + 2] = static_cast<float>(v.z);
  a[4 * i + 3] = 0.f;
}

}  // namespace

std::size_t GBuffer::hit_count() const {
  return static_cast<std::size_t>(
      std::count_if(triangle.begin(), triangle.end(), [](std::int32_t t) { return t >= 0; }));
}

void GBuffer::reset(int w, int h) {
  width = w;
  height = h;
  const std::size_t n = pixel_count();
  triangle.assign(n, -1);
  part.assign(n, -1);
  bary.assign(2 * n, 0.f);
  uv.assign(2 * n, 0.f);
  view_local.assign(4 * n, 0.f);
  normal.assign(4 * n, 0.f);
  direction.assign(4 * n, 0.f);
  depth.assign(n, kInf);
}

struct GBufferTracer::Impl {
  std::optional<EmbreeTriangleScene> embree;
  RTCScene scene = nullptr;  // embree->scene()
  std::vector<Vec3> positions;
  std::vector<std::uint32_t> indices;
  std::vector<std::uint16_t> triangle_part;
  std::vector<Vec2> uvs;
  std::vector<Vec3d> frame_t, frame_n;  // Mesh::frame of every vertex (b = n x t)
  Aabb bounds;
};

GBufferTracer::GBufferTracer(const Mesh& input) : impl_(std::make_unique<Impl>()) {
  if (input.triangle_count() == 0) throw ParameterError("GBufferTracer: the mesh has no triangles");
  Mesh completed;
  const Mesh* mesh = &mesh_with_frames(input, completed);
  Impl& im = *impl_;
  im.positions = mesh->positions;
  im.indices = mesh->indices;
  im.triangle_part = mesh->triangle_part;
  if (mesh->has_uvs()) {
    PRT_CHECK(mesh->uvs.size() == mesh->vertex_count(), "mesh has {} UVs for {} vertices",
              mesh->uvs.size(), mesh->vertex_count());
    im.uvs = mesh->uvs;
  }
  im.frame_t.resize(mesh->vertex_count());
  im.frame_n.resize(mesh->vertex_count());
  for (std::size_t v = 0; v < mesh->vertex_count(); ++v) {
    const LocalFrame f = mesh->frame(v);
    im.frame_t[v] = f.t;
    im.frame_n[v] = f.n;
  }

  im.bounds = mesh->bounds();
  im.embree.emplace(mesh->positions, mesh->indices);
  im.scene = im.embree->scene();
}

GBufferTracer::~GBufferTracer() = default;
GBufferTracer::GBufferTracer(GBufferTracer&&) noexcept = default;
GBufferTracer& GBufferTracer::operator=(GBufferTracer&&) noexcept = default;

GBuffer GBufferTracer::trace(const Camera& camera, PrimaryRays rays) const {
  GBuffer g;
  trace(camera, g, rays);
  return g;
}

namespace {

// Pixel columns [x0, x1) and rows [y0, y1) outside which no primary ray can meet the mesh's
// bounding box: the box's corners projected to the image plane, widened by two pixels so that
// rounding the ray direction to float cannot reach past it. The whole image when a corner
// lies at or behind the eye's plane (the projection is then unbounded).
struct PixelWindow {
  int x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  bool contains(int x, int y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
};

PixelWindow mesh_window(const Aabb& box, const Camera& camera, const CameraBasis& basis,
                        double sx_scale, double sy_scale) {
  PixelWindow all{0, camera.width, 0, camera.height};
  double lo_x = 1e300, hi_x = -1e300, lo_y = 1e300, hi_y = -1e300;
  for (int c = 0; c < 8; ++c) {
    const Vec3d p((c & 1) ? box.hi.x : box.lo.x, (c & 2) ? box.hi.y : box.lo.y,
                  (c & 4) ? box.hi.z : box.lo.z);
    const Vec3d q = p - camera.eye;
    const double z = glm::dot(q, basis.forward);
    if (!(z > 1e-9 * (1.0 + glm::length(q)))) return all;
    const double sx = glm::dot(q, basis.right) / z / sx_scale;
    const double sy = glm::dot(q, basis.up) / z / sy_scale;
    lo_x = std::min(lo_x, sx);
    hi_x = std::max(hi_x, sx);
    lo_y = std::min(lo_y, sy);
    hi_y = std::max(hi_y, sy);
  }
  // Pixel x's ray has sx = 2 (x + 0.5) / W - 1; row y's has sy = 1 - 2 (y + 0.5) / H.
  const auto clamp_to = [](double v, int n) {
    return static_cast<int>(std::clamp(v, 0.0, static_cast<double>(n)));
  };
  PixelWindow w;
  w.x0 = clamp_to(std::floor((lo_x + 1.0) * 0.5 * camera.width - 0.5) - 2, camera.width);
  w.x1 = clamp_to(std::ceil((hi_x + 1.0) * 0.5 * camera.width - 0.5) + 3, camera.width);
  w.y0 = clamp_to(std::floor((1.0 - hi_y) * 0.5 * camera.height - 0.5) - 2, camera.height);
  w.y1 = clamp_to(std::ceil((1.0 - lo_y) * 0.5 * camera.height - 0.5) + 3, camera.height);
  if (w.x0 >= w.x1 || w.y0 >= w.y1) w = PixelWindow{};
  return w;
}

// A pixel's miss values. A reused G-buffer's pixel that missed before already holds them (reset()
// or an earlier trace wrote them), so only previous hits are cleared.
void set_miss(GBuffer& g, std::size_t i) {
  if (g.triangle[i] < 0) return;
  g.triangle[i] = -1;
  g.part[i] = -1;
  g.bary[2 * i] = g.bary[2 * i + 1] = 0.f;
  g.uv[2 * i] = g.uv[2 * i + 1] = 0.f;
  for (int k = 0; k < 4; ++k) g.view_local[4 * i + k] = g.normal[4 * i + k] = 0.f;
  g.depth[i] = kInf;
}

}  // namespace

void GBufferTracer::trace(const Camera& camera, GBuffer& g, PrimaryRays rays) const {
  const CameraBasis basis = camera.basis();
  const Impl& im = *impl_;
  if (g.width != camera.width || g.height != camera.height || g.triangle.size() != g.pixel_count())
    g.reset(camera.width, camera.height);
  g.eye = camera.eye;
  const double sx_scale = basis.tan_half_fov_y * basis.aspect;
  const double sy_scale = basis.tan_half_fov_y;
  const float ox = static_cast<float>(camera.eye.x), oy = static_cast<float>(camera.eye.y),
              oz = static_cast<float>(camera.eye.z);
  const PixelWindow window = mesh_window(im.bounds, camera, basis, sx_scale, sy_scale);

  // The image-plane offsets of every column and row, computed once a frame rather than twice a
  // pixel (the same expressions, so the same directions).
  thread_local std::vector<double> column_sx, row_sy;
  std::vector<double>& sx_of = column_sx;
  std::vector<double>& sy_of = row_sy;
  sx_of.resize(static_cast<std::size_t>(camera.width));
  sy_of.resize(static_cast<std::size_t>(camera.height));
  for (int x = 0; x < camera.width; ++x)
    sx_of[x] = (2.0 * (x + 0.5) / camera.width - 1.0) * sx_scale;
  for (int y = 0; y < camera.height; ++y)
    sy_of[y] = (1.0 - 2.0 * (y + 0.5) / camera.height) * sy_scale;
  const auto direction = [&](int x, int y) {
    return glm::normalize(basis.forward + sx_of[x] * basis.right + sy_of[y] * basis.up);
  };
  // The hit's fields from Embree's (primID, u, v, t); ray direction d.
  const auto store_hit = [&](std::size_t i, const Vec3d& d, std::uint32_t tri, float u, float v,
                             float t) {
    const std::uint32_t* vi = &im.indices[3 * static_cast<std::size_t>(tri)];
    const double b1 = u, b2 = v, b0 = 1.0 - b1 - b2;
    g.triangle[i] = static_cast<std::int32_t>(tri);
    g.part[i] = im.triangle_part.empty() ? 0 : im.triangle_part[tri];
    g.bary[2 * i + 0] = u;
    g.bary[2 * i + 1] = v;
    g.depth[i] = t;
    if (!im.uvs.empty()) {
      const Vec2 uv = static_cast<float>(b0) * im.uvs[vi[0]] +
                      static_cast<float>(b1) * im.uvs[vi[1]] +
                      static_cast<float>(b2) * im.uvs[vi[2]];
      g.uv[2 * i + 0] = uv.x;
      g.uv[2 * i + 1] = uv.y;
    } else {
      g.uv[2 * i] = g.uv[2 * i + 1] = 0.f;
    }
    Vec3d n = b0 * im.frame_n[vi[0]] + b1 * im.frame_n[vi[1]] + b2 * im.frame_n[vi[2]];
    const double nl = glm::length(n);
    // Opposite vertex normals can cancel (a knife edge); the face normal stands in.
    if (!(nl > 1e-12)) {
      n = glm::cross(im.frame_n[vi[1]] - im.frame_n[vi[0]], im.frame_n[vi[2]] - im.frame_n[vi[0]]);
      n = glm::length(n) > 0 ? glm::normalize(n) : -d;
    } else {
      n /= nl;
    }
    const Vec3d t_sum = b0 * im.frame_t[vi[0]] + b1 * im.frame_t[vi[1]] + b2 * im.frame_t[vi[2]];
    const LocalFrame f = LocalFrame::from_unit_normal_tangent(n, t_sum);
    put4(g.normal, i, f.n);
    put4(g.view_local, i, f.to_local(-d));
  };

  if (rays == PrimaryRays::kRaster) {
    // Scratch reused between frames; trace() is const and may run on several threads.
    thread_local PrimaryHits scratch;
    PrimaryHits& hits = scratch;  // the lambda's workers must see this thread's scratch
    if (rasterize_primary(im.positions, im.indices, camera, basis, hits)) {
      tbb::parallel_for(
          tbb::blocked_range2d<int>(0, camera.height, kTile, 0, camera.width, kTile),
          [&](const tbb::blocked_range2d<int>& r) {
            for (int y = r.rows().begin(); y < r.rows().end(); ++y) {
              for (int x = r.cols().begin(); x < r.cols().end(); ++x) {
                const Vec3d d = direction(x, y);
                const std::size_t i = g.index(x, y);
                put4(g.direction, i, d);
                const std::int32_t tri = hits.triangle[i];
                if (tri < 0)
                  set_miss(g, i);
                else
                  store_hit(i, d, static_cast<std::uint32_t>(tri), hits.b1[i], hits.b2[i],
                            hits.t[i]);
              }
            }
          },
          tbb::simple_partitioner());
      return;
    }
    rays = PrimaryRays::kPackets;
  }
  tbb::parallel_for(
      tbb::blocked_range2d<int>(0, camera.height, kTile, 0, camera.width, kTile),
      [&](const tbb::blocked_range2d<int>& r) {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;  // one origin, neighbouring rays
        if (rays == PrimaryRays::kSingle) {
          for (int y = r.rows().begin(); y < r.rows().end(); ++y) {
            for (int x = r.cols().begin(); x < r.cols().end(); ++x) {
              const Vec3d d = direction(x, y);
              const std::size_t i = g.index(x, y);
              put4(g.direction, i, d);
              RTCRayHit rh{};
              rh.ray.org_x = ox;
              rh.ray.org_y = oy;
              rh.ray.org_z = oz;
              rh.ray.dir_x = static_cast<float>(d.x);
              rh.ray.dir_y = static_cast<float>(d.y);
              rh.ray.dir_z = static_cast<float>(d.z);
              rh.ray.tnear = 0.f;
              rh.ray.tfar = kInf;
              rh.ray.mask = ~0u;
              rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
              rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
              rtcIntersect1(im.scene, &context, &rh);
              if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
                set_miss(g, i);
              else
                store_hit(i, d, rh.hit.primID, rh.hit.u, rh.hit.v, rh.ray.tfar);
            }
          }
          return;
        }
        // Packets of 4 x 4 pixels; lanes outside the image or the mesh's window stay
        // invalid.
        for (int by = r.rows().begin(); by < r.rows().end(); by += 4) {
          for (int bx = r.cols().begin(); bx < r.cols().end(); bx += 4) {
            alignas(64) int valid[16];
            alignas(64) RTCRayHit16 rh;
            Vec3d dirs[16];
            bool any = false;
            for (int k = 0; k < 16; ++k) {
              const int x = bx + (k & 3), y = by + (k >> 2);
              valid[k] = 0;
              if (x >= r.cols().end() || y >= r.rows().end()) continue;
              const Vec3d d = direction(x, y);
              dirs[k] = d;
              const std::size_t i = g.index(x, y);
              put4(g.direction, i, d);
              set_miss(g, i);
              if (!window.contains(x, y)) continue;
              valid[k] = -1;
              any = true;
              rh.ray.org_x[k] = ox;
              rh.ray.org_y[k] = oy;
              rh.ray.org_z[k] = oz;
              rh.ray.dir_x[k] = static_cast<float>(d.x);
              rh.ray.dir_y[k] = static_cast<float>(d.y);
              rh.ray.dir_z[k] = static_cast<float>(d.z);
              rh.ray.tnear[k] = 0.f;
              rh.ray.tfar[k] = kInf;
              rh.ray.mask[k] = ~0u;
              rh.ray.time[k] = 0.f;
              rh.ray.flags[k] = 0;
              rh.ray.id[k] = static_cast<unsigned>(k);
              rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
              rh.hit.primID[k] = RTC_INVALID_GEOMETRY_ID;
              rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
            }
            if (!any) continue;
            rtcIntersect16(valid, im.scene, &context, &rh);
            for (int k = 0; k < 16; ++k) {
              if (!valid[k] || rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) continue;
              const int x = bx + (k & 3), y = by + (k >> 2);
              store_hit(g.index(x, y), dirs[k], rh.hit.primID[k], rh.hit.u[k], rh.hit.v[k],
                        rh.ray.tfar[k]);
            }
          }
        }
      },
      // Fixed tiles: which pixels share a packet never depends on the threads.
      tbb::simple_partitioner());
}

GBuffer render_gbuffer(const Mesh& mesh, const Camera& camera) {
  return GBufferTracer(mesh).trace(camera);
}

RgbImage gbuffer_image(const GBuffer& g, GBufferView view) {
  RgbImage img(g.width, g.height);
  const auto frac = [](float x) { return x - std::floor(x); };
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const std::size_t i = g.index(x, y);
      if (g.triangle[i] < 0) continue;
      Rgb c(0.f);
      switch (view) {
        case GBufferView::kNormal:
          c = 0.5f * Rgb(g.normal[4 * i], g.normal[4 * i + 1], g.normal[4 * i + 2]) + 0.5f;
          break;
        case GBufferView::kViewLocal:
          c = 0.5f * Rgb(g.view_local[4 * i], g.view_local[4 * i + 1], g.view_local[4 * i + 2]) +
              0.5f;
          break;
        case GBufferView::kUv:
          c = Rgb(frac(g.uv[2 * i]), frac(g.uv[2 * i + 1]), 0.f);
          break;
        case GBufferView::kUvChecker: {
          const float u = g.uv[2 * i], v = g.uv[2 * i + 1];
          const bool odd =
              (static_cast<long>(std::floor(4.f * u)) + static_cast<long>(std::floor(4.f * v))) & 1;
          const Rgb tint(0.35f + 0.65f * frac(u), 0.35f + 0.65f * frac(v), 0.6f);
          // Lit by the view direction so the shape stays readable.
          const float shade = 0.35f + 0.65f * std::max(0.f, g.view_local[4 * i + 2]);
          c = (odd ? 0.3f : 1.0f) * shade * tint;
          break;
        }
        case GBufferView::kPart: {
          // Golden-ratio hues: neighbouring part ids get distant colours.
          const float h = frac(0.61803398875f * static_cast<float>(g.part[i]) + 0.13f);
          const float shade = 0.35f + 0.65f * std::max(0.f, g.view_local[4 * i + 2]);
          const Rgb hue(std::clamp(std::abs(6.f * h - 3.f) - 1.f, 0.f, 1.f),
                        std::clamp(2.f - std::abs(6.f * h - 2.f), 0.f, 1.f),
                        std::clamp(2.f - std::abs(6.f * h - 4.f), 0.f, 1.f));
          c = shade * hue;
          break;
        }
      }
      img.at(x, y) = glm::clamp(c, Rgb(0.f), Rgb(1.f));
    }
  }
  return img;
}

void write_gbuffer_png(const GBuffer& gbuffer, GBufferView view,
                       const std::filesystem::path& file) {
  ToneMap tm;
  tm.auto_exposure = false;
  tm.exposure = 0;
  tm.gamma = 1.0;
  write_png(gbuffer_image(gbuffer, view), file, tm);
}

}  // namespace prt
