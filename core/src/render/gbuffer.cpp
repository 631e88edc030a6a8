#include "prtlab/render/gbuffer.h"

#include <embree3/rtcore.h>
#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <optional>
#include <string>

#include "geometry/embree_triangle_scene.h"
#include "prtlab/base/error.h"

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
  std::vector<std::uint32_t> indices;
  std::vector<std::uint16_t> triangle_part;
  std::vector<Vec2> uvs;
  std::vector<Vec3d> frame_t, frame_n;  // Mesh::frame of every vertex (b = n x t)
};

GBufferTracer::GBufferTracer(const Mesh& input) : impl_(std::make_unique<Impl>()) {
  if (input.triangle_count() == 0) throw ParameterError("GBufferTracer: the mesh has no triangles");
  Mesh completed;
  const Mesh* mesh = &mesh_with_frames(input, completed);
  Impl& im = *impl_;
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

  im.embree.emplace(mesh->positions, mesh->indices);
  im.scene = im.embree->scene();
}

GBufferTracer::~GBufferTracer() = default;
GBufferTracer::GBufferTracer(GBufferTracer&&) noexcept = default;
GBufferTracer& GBufferTracer::operator=(GBufferTracer&&) noexcept = default;

GBuffer GBufferTracer::trace(const Camera& camera) const {
  const CameraBasis basis = camera.basis();
  const Impl& im = *impl_;
  GBuffer g;
  g.reset(camera.width, camera.height);
  g.eye = camera.eye;
  const double sx_scale = basis.tan_half_fov_y * basis.aspect;
  const double sy_scale = basis.tan_half_fov_y;
  const float ox = static_cast<float>(camera.eye.x), oy = static_cast<float>(camera.eye.y),
              oz = static_cast<float>(camera.eye.z);

  tbb::parallel_for(
      tbb::blocked_range2d<int>(0, camera.height, kTile, 0, camera.width, kTile),
      [&](const tbb::blocked_range2d<int>& r) {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;  // one origin, neighbouring rays
        for (int y = r.rows().begin(); y < r.rows().end(); ++y) {
          const double sy = (1.0 - 2.0 * (y + 0.5) / camera.height) * sy_scale;
          for (int x = r.cols().begin(); x < r.cols().end(); ++x) {
            const double sx = (2.0 * (x + 0.5) / camera.width - 1.0) * sx_scale;
            const Vec3d d = glm::normalize(basis.forward + sx * basis.right + sy * basis.up);
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
            if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;

            const std::uint32_t tri = rh.hit.primID;
            const std::uint32_t* v = &im.indices[3 * static_cast<std::size_t>(tri)];
            const double b1 = rh.hit.u, b2 = rh.hit.v, b0 = 1.0 - b1 - b2;
            g.triangle[i] = static_cast<std::int32_t>(tri);
            g.part[i] = im.triangle_part.empty() ? 0 : im.triangle_part[tri];
            g.bary[2 * i + 0] = rh.hit.u;
            g.bary[2 * i + 1] = rh.hit.v;
            g.depth[i] = rh.ray.tfar;
            if (!im.uvs.empty()) {
              const Vec2 uv = static_cast<float>(b0) * im.uvs[v[0]] +
                              static_cast<float>(b1) * im.uvs[v[1]] +
                              static_cast<float>(b2) * im.uvs[v[2]];
              g.uv[2 * i + 0] = uv.x;
              g.uv[2 * i + 1] = uv.y;
            }
            Vec3d n = b0 * im.frame_n[v[0]] + b1 * im.frame_n[v[1]] + b2 * im.frame_n[v[2]];
            const double nl = glm::length(n);
            // Opposite vertex normals can cancel (a knife edge); the face normal stands in.
            if (!(nl > 1e-12)) {
              n = glm::cross(im.frame_n[v[1]] - im.frame_n[v[0]],
                             im.frame_n[v[2]] - im.frame_n[v[0]]);
              n = glm::length(n) > 0 ? glm::normalize(n) : -d;
            } else {
              n /= nl;
            }
            const Vec3d t_sum =
                b0 * im.frame_t[v[0]] + b1 * im.frame_t[v[1]] + b2 * im.frame_t[v[2]];
            const LocalFrame f = LocalFrame::from_normal_tangent(n, t_sum);
            put4(g.normal, i, f.n);
            put4(g.view_local, i, f.to_local(-d));
          }
        }
      });
  return g;
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
