#include "prtlab/transfer/visibility.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <string>

#include "geometry/embree_triangle_scene.h"
#include "prtlab/sphere/cubemap.h"
#include "prtlab/base/error.h"
#include "prtlab/base/log.h"

namespace prt {

namespace {

// Solid angle of [0, x] x [0, y] on the plane at unit distance (gnomonic projection);
// inclusion-exclusion over a rectangle's corners gives its exact solid angle.
double corner_area(double x, double y) {
  return std::atan2(x * y, std::sqrt(x * x + y * y + 1.0));
}

double rect_solid_angle(double s0, double s1, double t0, double t1) {
  return corner_area(s1, t1) - corner_area(s0, t1) - corner_area(s1, t0) + corner_area(s0, t0);
}

}  // namespace

SupersampledCubemap::SupersampledCubemap(int resolution, int supersampling)
    : r_(resolution), s_(supersampling) {
  if (resolution < 1 || resolution > 4096) {
    throw ParameterError(
        fmt::format("cubemap resolution must be in [1, 4096], got {}", resolution));
  }
  // Counts are stored as uint8, so s^2 <= 255.
  if (supersampling < 1 || supersampling > 15) {
    throw ParameterError(fmt::format(
        "supersampling must be in [1, 15] (s^2 counts fit in a byte), got {}", supersampling));
  }
  const int sr = r_ * s_;
  const std::size_t n = static_cast<std::size_t>(6) * sr * sr;
  // Sub-ray ids are 32-bit (visibility()'s unblocked list).
  if (n > 0xffffffffull) {
    throw ParameterError(
        fmt::format("{} sub-rays per point (R = {}, s = {}) exceed 2^32", n, r_, s_));
  }
  dir_x_.resize(n);
  dir_y_.resize(n);
  dir_z_.resize(n);
  solid_angle_.resize(n);
  auto coord = [&](int i) { return 2.0 * i / sr - 1.0; };
  std::size_t r = 0;
  for (int face = 0; face < 6; ++face) {
    for (int y = 0; y < r_; ++y) {
      for (int x = 0; x < r_; ++x) {
        for (int sy = 0; sy < s_; ++sy) {
          for (int sx = 0; sx < s_; ++sx, ++r) {
            const int gx = x * s_ + sx, gy = y * s_ + sy;
            const double s0 = coord(gx), s1 = coord(gx + 1), t0 = coord(gy), t1 = coord(gy + 1);
            const Vec3d d = CubemapLayout::face_direction(face, 0.5 * (s0 + s1), 0.5 * (t0 + t1));
            dir_x_[r] = static_cast<float>(d.x);
            dir_y_[r] = static_cast<float>(d.y);
            dir_z_[r] = static_cast<float>(d.z);
            solid_angle_[r] = rect_solid_angle(s0, s1, t0, t1);
          }
        }
      }
    }
  }
}

void SupersampledCubemap::subpixel_bounds(std::size_t r, int& face, double& s0, double& s1,
                                          double& t0, double& t1) const {
  const std::size_t ss = static_cast<std::size_t>(s_) * s_;
  const std::size_t k = r / ss, sub = r % ss;
  face = static_cast<int>(k / (static_cast<std::size_t>(r_) * r_));
  const int p = static_cast<int>(k % (static_cast<std::size_t>(r_) * r_));
  const int gx = (p % r_) * s_ + static_cast<int>(sub % s_);
  const int gy = (p / r_) * s_ + static_cast<int>(sub / s_);
  const int sr = r_ * s_;
  s0 = 2.0 * gx / sr - 1.0;
  s1 = 2.0 * (gx + 1) / sr - 1.0;
  t0 = 2.0 * gy / sr - 1.0;
  t1 = 2.0 * (gy + 1) / sr - 1.0;
}

// ---------------------------------------------------------------------------------------------

namespace {}  // namespace

struct EmbreeScene::Impl {
  EmbreeTriangleScene embree;
  double diagonal = 0.0;
  double offset = 0.0;
  RTCScene scene = nullptr;  // embree.scene(), read on every ray
};

EmbreeScene::EmbreeScene(const Mesh& mesh, double offset_relative) {
  if (mesh.triangle_count() == 0) throw ParameterError("EmbreeScene: the mesh has no triangles");
  if (!(offset_relative >= 0.0)) throw ParameterError("EmbreeScene: the ray offset must be >= 0");
  impl_ = std::make_unique<Impl>(Impl{EmbreeTriangleScene(mesh.positions, mesh.indices)});
  const Aabb box = mesh.bounds();
  impl_->diagonal = glm::length(Vec3d(box.hi) - Vec3d(box.lo));
  impl_->offset = offset_relative * impl_->diagonal;
  impl_->scene = impl_->embree.scene();
}

EmbreeScene::~EmbreeScene() = default;
EmbreeScene::EmbreeScene(EmbreeScene&&) noexcept = default;
EmbreeScene& EmbreeScene::operator=(EmbreeScene&&) noexcept = default;

double EmbreeScene::bounds_diagonal() const {
  return impl_->diagonal;
}
double EmbreeScene::ray_offset() const {
  return impl_->offset;
}

bool EmbreeScene::occluded(const Vec3d& origin, const Vec3d& dir, double tnear, double tfar) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay ray{};
  ray.org_x = static_cast<float>(origin.x);
  ray.org_y = static_cast<float>(origin.y);
  ray.org_z = static_cast<float>(origin.z);
  ray.dir_x = static_cast<float>(dir.x);
  ray.dir_y = static_cast<float>(dir.y);
  ray.dir_z = static_cast<float>(dir.z);
  ray.tnear = static_cast<float>(tnear);
  ray.tfar = static_cast<float>(
      std::min(tfar, static_cast<double>(std::numeric_limits<float>::infinity())));
  ray.mask = ~0u;
  ray.flags = 0;
  ray.time = 0.f;
  rtcOccluded1(impl_->scene, &context, &ray);
  // Embree marks an occluded ray by setting tfar to -inf.
  return ray.tfar < 0.f;
}

namespace {

// Packet width: 8 matches AVX2 (the widest ISA of the target machines); rtcOccluded16 is
// emulated as two 8-wide halves there. bench numbers in docs/transfer.md.
constexpr int kPacket = 8;
using RayPacket = RTCRay8;
inline void occluded_packet(const int* valid, RTCScene scene, RTCIntersectContext* ctx,
                            RayPacket* ray) {
  rtcOccluded8(valid, scene, ctx, ray);
}

}  // namespace

std::uint64_t EmbreeScene::visibility(const SupersampledCubemap& dirs, const Vec3d& position,
                                      const Vec3d& normal, std::span<std::uint8_t> counts,
                                      std::vector<std::uint32_t>* unblocked) const {
  PRT_CHECK(counts.size() == static_cast<std::size_t>(dirs.pixel_count()),
            "visibility: counts has {} entries, N = {}", counts.size(), dirs.pixel_count());
  std::fill(counts.begin(), counts.end(), std::uint8_t{0});
  if (unblocked) unblocked->clear();

  const Vec3d o = position + impl_->offset * normal;
  const float ox = static_cast<float>(o.x), oy = static_cast<float>(o.y),
              oz = static_cast<float>(o.z);
  const float nx = static_cast<float>(normal.x), ny = static_cast<float>(normal.y),
              nz = static_cast<float>(normal.z);
  const float* dx = dirs.dir_x().data();
  const float* dy = dirs.dir_y().data();
  const float* dz = dirs.dir_z().data();
  const std::size_t total = dirs.subray_count();
  const std::size_t per_pixel = static_cast<std::size_t>(dirs.subrays_per_pixel());
  const std::size_t per_face = total / 6;

  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;  // one origin, neighbouring directions

  RayPacket ray;
  for (int i = 0; i < kPacket; ++i) {
    ray.org_x[i] = ox;
    ray.org_y[i] = oy;
    ray.org_z[i] = oz;
    ray.time[i] = 0.f;
    ray.mask[i] = ~0u;
    ray.id[i] = static_cast<unsigned>(i);
    ray.flags[i] = 0;
  }
  alignas(32) std::array<int, kPacket> valid{};
  std::uint64_t traced = 0;

  for (int face = 0; face < 6; ++face) {
    // A face whose four corner directions are all on or below the tangent plane lies wholly
    // below it (the face is the convex hull of its corners on the sphere): skip it.
    bool any_above = false;
    for (double cs : {-1.0, 1.0})
      for (double ct : {-1.0, 1.0})
        any_above |= glm::dot(CubemapLayout::face_direction(face, cs, ct), normal) > 0.0;
    if (!any_above) continue;

    const std::size_t face_end = (face + 1) * per_face;
    for (std::size_t base = face * per_face; base < face_end; base += kPacket) {
      const int width = static_cast<int>(std::min<std::size_t>(kPacket, face_end - base));
      int active = 0;
      for (int i = 0; i < kPacket; ++i) {
        const std::size_t r = base + static_cast<std::size_t>(i);
        const bool above = i < width && dx[r] * nx + dy[r] * ny + dz[r] * nz > 0.f;
        valid[i] = above ? -1 : 0;
        active += above;
      }
      if (active == 0) continue;
      for (int i = 0; i < width; ++i) {
        const std::size_t r = base + static_cast<std::size_t>(i);
        ray.dir_x[i] = dx[r];
        ray.dir_y[i] = dy[r];
        ray.dir_z[i] = dz[r];
        ray.tnear[i] = 0.f;
        ray.tfar[i] = std::numeric_limits<float>::infinity();
      }
      occluded_packet(valid.data(), impl_->scene, &context, &ray);
      traced += static_cast<std::uint64_t>(active);
      for (int i = 0; i < width; ++i) {
        if (valid[i] && ray.tfar[i] >= 0.f) {
          const std::size_t r = base + static_cast<std::size_t>(i);
          ++counts[r / per_pixel];
          if (unblocked) unblocked->push_back(static_cast<std::uint32_t>(r));
        }
      }
    }
  }
  return traced;
}

}  // namespace prt
