#include "prtlab/geometry/mesh.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <unordered_map>

#include "prtlab/base/error.h"

namespace prt {
namespace {

struct PositionKey {
  std::uint32_t x, y, z;
  bool operator==(const PositionKey&) const = default;
};

struct PositionKeyHash {
  std::size_t operator()(const PositionKey& k) const {
    std::uint64_t h = k.x * 0x9E3779B97F4A7C15ull;
    h ^= (k.y + 0x7F4A7C15ull + (h << 6) + (h >> 2)) * 0xBF58476D1CE4E5B9ull;
    h ^= (k.z + 0x94D049BB1331ull + (h << 6) + (h >> 2)) * 0x94D049BB133111EBull;
    return static_cast<std::size_t>(h ^ (h >> 31));
  }
};

std::uint32_t float_key(float f) {
  if (f == 0.f) f = 0.f;  // -0 and +0 are the same position
  std::uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return u;
}

Vec3d to_d(const Vec3& v) {
  return Vec3d(v);
}

Vec3d normalized_or_zero(const Vec3d& v) {
  const double len = glm::length(v);
  return len > 0.0 && std::isfinite(len) ? v / len : Vec3d(0.0);
}

}  // namespace

Aabb Mesh::bounds() const {
  if (positions.empty()) return {};
  Aabb box{positions[0], positions[0]};
  for (const Vec3& p : positions) {
    box.lo = glm::min(box.lo, p);
    box.hi = glm::max(box.hi, p);
  }
  return box;
}

LocalFrame Mesh::frame(std::size_t v) const {
  PRT_CHECK(v < normals.size(), "Mesh::frame({}) needs normals ({} present)", v, normals.size());
  if (v < tangents.size())
    return LocalFrame::from_normal_tangent(to_d(normals[v]), to_d(tangents[v]));
  return LocalFrame::from_normal(to_d(normals[v]));
}

void Mesh::append(const Mesh& other, std::uint16_t part) {
  if (other.positions.empty() && other.indices.empty()) return;
  const bool this_empty = positions.empty() && indices.empty();
  const std::size_t offset = positions.size();
  PRT_CHECK(offset + other.positions.size() <= std::numeric_limits<std::uint32_t>::max(),
            "mesh too large for 32-bit indices");

  // Complete an attribute that only one side has, so that the merged mesh stays consistent.
  const Mesh* src = &other;
  Mesh completed;
  const bool need_normals = !this_empty && !normals.empty() && other.normals.empty();
  const bool need_tangents = !this_empty && !tangents.empty() && other.tangents.empty();
  if (need_normals || need_tangents) {
    completed = other;
    if (need_normals) compute_smooth_normals(completed);
    if (need_tangents) compute_tangents(completed);
    src = &completed;
  }
  if (!this_empty && normals.empty() && !src->normals.empty()) compute_smooth_normals(*this);
  if (!this_empty && tangents.empty() && !src->tangents.empty()) compute_tangents(*this);
  if (!this_empty && uvs.empty() && src->has_uvs()) uvs.assign(positions.size(), Vec2(0.f));

  positions.insert(positions.end(), src->positions.begin(), src->positions.end());
  if (!normals.empty() || this_empty)
    normals.insert(normals.end(), src->normals.begin(), src->normals.end());
  if (!tangents.empty() || this_empty)
    tangents.insert(tangents.end(), src->tangents.begin(), src->tangents.end());
  if (has_uvs()) {
    if (src->has_uvs())
      uvs.insert(uvs.end(), src->uvs.begin(), src->uvs.end());
    else
      uvs.resize(positions.size(), Vec2(0.f));
  } else if (this_empty) {
    uvs = src->uvs;
  }

  const std::size_t old_triangles = triangle_count();
  indices.reserve(indices.size() + src->indices.size());
  for (std::uint32_t i : src->indices) indices.push_back(static_cast<std::uint32_t>(i + offset));

  const bool parts_needed = part != 0 || !src->triangle_part.empty() || !triangle_part.empty();
  if (parts_needed) {
    triangle_part.resize(old_triangles, 0);
    for (std::size_t t = 0; t < src->triangle_count(); ++t) {
      const unsigned p = unsigned{part} + src->part_of(t);
      PRT_CHECK(p <= std::numeric_limits<std::uint16_t>::max(), "part id {} overflows", p);
      triangle_part.push_back(static_cast<std::uint16_t>(p));
    }
  }
}

std::vector<std::uint32_t> position_representatives(const Mesh& mesh) {
  std::vector<std::uint32_t> rep(mesh.vertex_count());
  std::unordered_map<PositionKey, std::uint32_t, PositionKeyHash> first;
  first.reserve(mesh.vertex_count());
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    const Vec3& p = mesh.positions[v];
    const auto [it, inserted] = first.try_emplace(
        PositionKey{float_key(p.x), float_key(p.y), float_key(p.z)}, static_cast<std::uint32_t>(v));
    rep[v] = it->second;
  }
  return rep;
}

const Mesh& mesh_with_frames(const Mesh& input, Mesh& storage) {
  if (input.normals.size() == input.vertex_count() && input.tangents.size() == input.vertex_count())
    return input;
  storage = input;
  if (storage.normals.size() != storage.vertex_count()) compute_smooth_normals(storage);
  compute_tangents(storage);
  return storage;
}

void compute_smooth_normals(Mesh& mesh) {
  const std::size_t n = mesh.vertex_count();
  std::vector<Vec3d> acc(n, Vec3d(0.0));
  std::vector<Vec3d> area_acc(n, Vec3d(0.0));
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const std::uint32_t* tri = &mesh.indices[3 * t];
    PRT_CHECK(tri[0] < n && tri[1] < n && tri[2] < n, "triangle {} has an index out of range", t);
    const Vec3d p[3] = {to_d(mesh.positions[tri[0]]), to_d(mesh.positions[tri[1]]),
                        to_d(mesh.positions[tri[2]])};
    const Vec3d cross = glm::cross(p[1] - p[0], p[2] - p[0]);
    const Vec3d face = normalized_or_zero(cross);
    if (face == Vec3d(0.0)) continue;
    for (int c = 0; c < 3; ++c) {
      const Vec3d e1 = p[(c + 1) % 3] - p[c];
      const Vec3d e2 = p[(c + 2) % 3] - p[c];
      // atan2 of |cross| and dot stays accurate for very small and very obtuse angles.
      const double angle = std::atan2(glm::length(glm::cross(e1, e2)), glm::dot(e1, e2));
      acc[tri[c]] += angle * face;
      area_acc[tri[c]] += cross;
    }
  }
  std::vector<Vec3d> own(n);
  for (std::size_t v = 0; v < n; ++v) {
    own[v] = normalized_or_zero(acc[v]);
    if (own[v] == Vec3d(0.0)) own[v] = normalized_or_zero(area_acc[v]);
  }

  // Vertices at one position: smooth across a seam, not across a crease.
  const std::vector<std::uint32_t> rep = position_representatives(mesh);
  std::vector<std::vector<std::uint32_t>> groups;
  std::vector<std::int64_t> group_of(n, -1);
  for (std::size_t v = 0; v < n; ++v) {
    if (rep[v] == v) continue;
    std::int64_t& g = group_of[rep[v]];
    if (g < 0) {
      g = static_cast<std::int64_t>(groups.size());
      groups.push_back({rep[v]});
    }
    groups[static_cast<std::size_t>(g)].push_back(static_cast<std::uint32_t>(v));
  }
  constexpr double kCosCrease = 0.5;  // 60 degrees
  std::vector<Vec3d> merged = acc;
  for (const auto& members : groups) {
    for (std::uint32_t v : members) {
      Vec3d sum(0.0);
      for (std::uint32_t w : members)
        if (w == v || glm::dot(own[v], own[w]) > kCosCrease) sum += acc[w];
      merged[v] = sum;
    }
  }

  mesh.normals.resize(n);
  for (std::size_t v = 0; v < n; ++v) {
    Vec3d nv = normalized_or_zero(merged[v]);
    if (nv == Vec3d(0.0)) nv = own[v];
    // A vertex without a usable triangle still needs a unit normal; +z is as good as any.
    if (nv == Vec3d(0.0)) nv = Vec3d(0.0, 0.0, 1.0);
    mesh.normals[v] = Vec3(nv);
  }
}

void compute_tangents(Mesh& mesh) {
  const std::size_t n = mesh.vertex_count();
  if (mesh.normals.size() != n) compute_smooth_normals(mesh);
  std::vector<Vec3d> acc(n, Vec3d(0.0));
  if (mesh.has_uvs()) {
    PRT_CHECK(mesh.uvs.size() == n, "mesh has {} UVs for {} vertices", mesh.uvs.size(), n);
    // Lengyel 2001: solve [e1 e2] = [T B] [du1 du2; dv1 dv2] for T = dp/du per triangle.
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
      const std::uint32_t* tri = &mesh.indices[3 * t];
      const Vec3d p0 = to_d(mesh.positions[tri[0]]);
      const Vec3d e1 = to_d(mesh.positions[tri[1]]) - p0;
      const Vec3d e2 = to_d(mesh.positions[tri[2]]) - p0;
      const Vec2d w0 = Vec2d(mesh.uvs[tri[0]]);
      const Vec2d d1 = Vec2d(mesh.uvs[tri[1]]) - w0;
      const Vec2d d2 = Vec2d(mesh.uvs[tri[2]]) - w0;
      const double det = d1.x * d2.y - d2.x * d1.y;
      if (det == 0.0 || !std::isfinite(det)) continue;
      const Vec3d sdir = (e1 * d2.y - e2 * d1.y) / det;
      if (!std::isfinite(glm::dot(sdir, sdir))) continue;
      for (int c = 0; c < 3; ++c) acc[tri[c]] += sdir;
    }
  }
  mesh.tangents.resize(n);
  for (std::size_t v = 0; v < n; ++v) {
    const Vec3d nv = to_d(mesh.normals[v]);
    const LocalFrame f = acc[v] == Vec3d(0.0) ? LocalFrame::from_normal(nv)
                                              : LocalFrame::from_normal_tangent(nv, acc[v]);
    mesh.tangents[v] = Vec3(f.t);
  }
}

}  // namespace prt
