#include "prtlab/sphere/icosphere.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <utility>

#include "prtlab/base/error.h"

namespace prt {

int icosphere_vertex_count(int level) {
  if (level < 0 || level > kMaxIcosphereLevel)
    throw ParameterError(
        fmt::format("icosphere level {} is not in 0..{}", level, kMaxIcosphereLevel));
  return 10 * (1 << (2 * level)) + 2;
}

std::vector<Vec3d> icosphere_vertices(int level) {
  (void)icosphere_vertex_count(level);
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                          {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                          {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p = glm::normalize(p);
  std::vector<std::array<int, 3>> faces = {
      {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int k = 0; k < level; ++k) {
    std::map<std::pair<int, int>, int> midpoint;
    const auto mid = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto [it, fresh] = midpoint.emplace(key, static_cast<int>(v.size()));
      if (fresh)
        v.push_back(
            glm::normalize(v[static_cast<std::size_t>(a)] + v[static_cast<std::size_t>(b)]));
      return it->second;
    };
    std::vector<std::array<int, 3>> next;
    next.reserve(faces.size() * 4);
    for (const auto& f : faces) {
      const int ab = mid(f[0], f[1]), bc = mid(f[1], f[2]), ca = mid(f[2], f[0]);
      next.push_back({f[0], ab, ca});
      next.push_back({f[1], bc, ab});
      next.push_back({f[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    faces = std::move(next);
  }
  PRT_CHECK(static_cast<int>(v.size()) == icosphere_vertex_count(level),
            "icosphere level {}: {} vertices", level, v.size());
  return v;
}

int icosphere_level_for_count(int count) {
  for (int level = 0; level <= kMaxIcosphereLevel; ++level)
    if (icosphere_vertex_count(level) == count) return level;
  std::string known;
  for (int level = 0; level <= kMaxIcosphereLevel; ++level)
    known += (known.empty() ? "" : ", ") + std::to_string(icosphere_vertex_count(level));
  throw ParameterError(fmt::format(
      "{} is no icosphere vertex count (the subdivided icosahedron has {})", count, known));
}

double min_geodesic_distance(std::span<const Vec3d> points) {
  if (points.size() < 2) throw ParameterError("min_geodesic_distance: fewer than two points");
  // The largest dot product is the smallest angle; acos once at the end.
  const double best = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, points.size()), -1.0,
      [&](const tbb::blocked_range<std::size_t>& r, double acc) {
        for (std::size_t i = r.begin(); i != r.end(); ++i)
          for (std::size_t j = i + 1; j < points.size(); ++j)
            acc = std::max(acc, glm::dot(points[i], points[j]));
        return acc;
      },
      [](double a, double b) { return std::max(a, b); });
  return std::acos(std::clamp(best, -1.0, 1.0));
}

}  // namespace prt
