#include "prtlab/geometry/mesh_processing.h"

#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <unordered_map>
#include <utility>

#include "prtlab/base/error.h"
#include "prtlab/base/log.h"

namespace prt {
namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t{a} << 32) | b;
}

std::uint32_t bits(float f) {
  if (f == 0.f) f = 0.f;  // -0 and +0 weld
  std::uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return u;
}

/// Keeps the vertices that `indices` use (in their order) and remaps the indices; UVs follow,
/// `parts` becomes the triangle parts. Normals and tangents are dropped (callers recompute).
Mesh compact_vertices(const Mesh& mesh, std::vector<std::uint32_t> indices,
                      std::vector<std::uint16_t> parts) {
  std::vector<std::uint32_t> remap(mesh.vertex_count(), kNone);
  for (std::uint32_t i : indices) remap[i] = 0;
  Mesh out;
  std::uint32_t next = 0;
  for (std::size_t v = 0; v < remap.size(); ++v) {
    if (remap[v] == kNone) continue;
    remap[v] = next++;
    out.positions.push_back(mesh.positions[v]);
    if (mesh.has_uvs()) out.uvs.push_back(mesh.uvs[v]);
  }
  for (std::uint32_t& i : indices) i = remap[i];
  out.indices = std::move(indices);
  out.triangle_part = std::move(parts);
  return out;
}

/// Vertices used by triangles of more than one part are duplicated per part, so that no
/// simplification can make a triangle span two parts. Returns the part of every vertex.
std::vector<std::uint16_t> split_vertices_by_part(Mesh& mesh) {
  std::vector<std::uint16_t> part_of(mesh.vertex_count(), 0);
  if (mesh.triangle_part.empty()) return part_of;
  std::vector<std::uint8_t> seen(mesh.vertex_count(), 0);
  std::unordered_map<std::uint64_t, std::uint32_t> copies;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const std::uint16_t p = mesh.triangle_part[t];
    for (int c = 0; c < 3; ++c) {
      std::uint32_t& idx = mesh.indices[3 * t + static_cast<std::size_t>(c)];
      if (!seen[idx]) {
        seen[idx] = 1;
        part_of[idx] = p;
        continue;
      }
      if (part_of[idx] == p) continue;
      const auto [it, inserted] = copies.try_emplace((std::uint64_t{idx} << 16) | p, 0);
      if (inserted) {
        it->second = static_cast<std::uint32_t>(mesh.positions.size());
        mesh.positions.push_back(mesh.positions[idx]);
        if (mesh.has_uvs()) mesh.uvs.push_back(mesh.uvs[idx]);
        part_of.push_back(p);
        seen.push_back(1);
      }
      idx = it->second;
    }
  }
  return part_of;
}

void finish_attributes(Mesh& mesh) {
  compute_smooth_normals(mesh);
  compute_tangents(mesh);
}

/// meshopt_simplify (0.18) can fold a valence-3 vertex onto its neighbours, leaving two
/// triangles over the same three vertices back to back (a zero-volume fin). Opposite pairs
/// cancel; repeated copies of one orientation keep one.
void remove_fins(std::vector<std::uint32_t>& indices) {
  struct Set {
    std::uint32_t v[3];
    bool operator==(const Set&) const = default;
  };
  struct SetHash {
    std::size_t operator()(const Set& s) const {
      std::uint64_t h = s.v[0] * 0x9E3779B97F4A7C15ull;
      h = (h ^ s.v[1]) * 0xBF58476D1CE4E5B9ull;
      h = (h ^ s.v[2]) * 0x94D049BB133111EBull;
      return static_cast<std::size_t>(h ^ (h >> 29));
    }
  };
  struct Count {
    int even = 0, odd = 0;
    bool done = false;
  };
  // Sorted corners; `odd` tells whether sorting took an odd permutation (opposite winding).
  const auto set_of = [](const std::uint32_t* t, bool& odd) {
    Set s{{t[0], t[1], t[2]}};
    odd = false;
    const auto order = [&](int i, int j) {
      if (s.v[i] > s.v[j]) std::swap(s.v[i], s.v[j]), odd = !odd;
    };
    order(0, 1), order(1, 2), order(0, 1);
    return s;
  };
  const std::size_t T = indices.size() / 3;
  std::unordered_map<Set, Count, SetHash> sets;
  sets.reserve(T);
  bool odd = false;
  for (std::size_t t = 0; t < T; ++t) {
    Count& c = sets[set_of(&indices[3 * t], odd)];
    ++(odd ? c.odd : c.even);
  }
  if (sets.size() == T) return;  // no two triangles share their corners
  std::size_t kept = 0;
  for (std::size_t t = 0; t < T; ++t) {
    Count& c = sets[set_of(&indices[3 * t], odd)];
    if (c.done || c.even == c.odd) continue;
    if (odd != (c.odd > c.even)) continue;  // the minority orientation
    c.done = true;
    std::copy_n(&indices[3 * t], 3, &indices[3 * kept]);
    ++kept;
  }
  indices.resize(3 * kept);
}

/// The outcome of one simplification at a given target index count.
struct Simplified {
  std::vector<std::uint32_t> indices;
  std::size_t vertices = 0;
};

class Simplifier {
 public:
  Simplifier(const Mesh& mesh, bool sloppy)
      : mesh_(mesh), sloppy_(sloppy), mark_(mesh.vertex_count(), 0) {}

  int runs() const { return runs_; }

  Simplified run(std::size_t target_indices) {
    ++runs_;
    Simplified s;
    s.indices.resize(mesh_.indices.size());
    const float* pos = &mesh_.positions[0].x;
    // target_error 1 (the whole extent): the vertex count, not the error, decides where to stop.
    const std::size_t n =
        sloppy_ ? meshopt_simplifySloppy(s.indices.data(), mesh_.indices.data(),
                                         mesh_.indices.size(), pos, mesh_.vertex_count(),
                                         sizeof(Vec3), target_indices, 1.0f, nullptr)
                : meshopt_simplify(s.indices.data(), mesh_.indices.data(), mesh_.indices.size(),
                                   pos, mesh_.vertex_count(), sizeof(Vec3), target_indices, 1.0f, 0,
                                   nullptr);
    s.indices.resize(n);
    remove_fins(s.indices);
    ++stamp_;
    for (std::uint32_t i : s.indices) {
      if (mark_[i] != stamp_) {
        mark_[i] = stamp_;
        ++s.vertices;
      }
    }
    return s;
  }

 private:
  const Mesh& mesh_;
  bool sloppy_;
  std::vector<std::uint32_t> mark_;
  std::uint32_t stamp_ = 0;
  int runs_ = 0;
};

std::size_t diff(std::size_t a, std::size_t b) {
  return a > b ? a - b : b - a;
}

/// Searches the target index count whose result has `target` vertices. The vertex count grows
/// with the index target (about one vertex per six indices on a closed mesh) in small, slightly
/// noisy steps: regula falsi inside a bracket, bisecting when one end stops moving.
Simplified search_target(const Mesh& mesh, std::size_t target, bool sloppy) {
  Simplifier simplifier(mesh, sloppy);
  const std::size_t I = mesh.indices.size();
  const auto round3 = [](double x) {
    return static_cast<std::size_t>(std::max(0.0, std::round(x / 3.0))) * 3;
  };
  std::size_t lo = 0, hi = I;  // the counts at lo and hi are below and above the target
  double v_lo = 0.0, v_hi = static_cast<double>(mesh.vertex_count());
  Simplified best;
  bool have_best = false;
  std::size_t guess = round3(static_cast<double>(I) * static_cast<double>(target) / v_hi);
  int last_end = 0, repeats = 0;
  for (int iter = 0; iter < 64 && hi - lo > 3; ++iter) {
    guess = std::clamp(guess, lo + 3, hi - 3);
    Simplified s = simplifier.run(guess);
    const std::size_t got = s.vertices;
    if (!have_best || diff(got, target) < diff(best.vertices, target)) {
      best = std::move(s);
      have_best = true;
    }
    if (got == target) break;
    const int end = got < target ? -1 : 1;
    if (end < 0) {
      lo = guess;
      v_lo = static_cast<double>(got);
    } else {
      hi = guess;
      v_hi = static_cast<double>(got);
    }
    repeats = end == last_end ? repeats + 1 : 0;
    last_end = end;
    if (repeats >= 2 || v_hi <= v_lo) {
      guess = lo + round3(static_cast<double>(hi - lo) / 2.0);
      repeats = 0;
    } else {
      guess = lo + round3((static_cast<double>(target) - v_lo) * static_cast<double>(hi - lo) /
                          (v_hi - v_lo));
    }
  }
  if (!have_best) best = simplifier.run(hi);
  log_debug("decimation{}: {} vertices after {} simplifications (target {})",
            sloppy ? " (sloppy)" : "", best.vertices, simplifier.runs(), target);
  return best;
}

struct WeldKeyValue {
  std::uint32_t p[3];
  std::uint32_t uv[2];
  bool operator==(const WeldKeyValue&) const = default;
};
struct WeldKeyHash {
  std::size_t operator()(const WeldKeyValue& k) const {
    std::uint64_t h = 0xCBF29CE484222325ull;
    for (std::uint32_t w : {k.p[0], k.p[1], k.p[2], k.uv[0], k.uv[1]}) {
      h ^= w;
      h *= 0x100000001B3ull;
      h ^= h >> 29;
    }
    return static_cast<std::size_t>(h);
  }
};

/// Welding without the normal and tangent recomputation (callers recompute once at the end).
Mesh weld_core(const Mesh& mesh, WeldKey key) {
  const bool use_uv = key == WeldKey::kPositionAndUv && mesh.has_uvs();
  std::unordered_map<WeldKeyValue, std::uint32_t, WeldKeyHash> first;
  first.reserve(mesh.vertex_count());
  std::vector<std::uint32_t> remap(mesh.vertex_count());
  Mesh welded;
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    const Vec3& p = mesh.positions[v];
    WeldKeyValue k{{bits(p.x), bits(p.y), bits(p.z)}, {0, 0}};
    if (use_uv) k.uv[0] = bits(mesh.uvs[v].x), k.uv[1] = bits(mesh.uvs[v].y);
    const auto [it, inserted] =
        first.try_emplace(k, static_cast<std::uint32_t>(welded.positions.size()));
    if (inserted) {
      welded.positions.push_back(p);
      if (use_uv) welded.uvs.push_back(mesh.uvs[v]);
    }
    remap[v] = it->second;
  }
  std::vector<std::uint32_t> indices;
  std::vector<std::uint16_t> parts;
  indices.reserve(mesh.indices.size());
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const std::uint32_t a = remap[mesh.indices[3 * t]], b = remap[mesh.indices[3 * t + 1]],
                        c = remap[mesh.indices[3 * t + 2]];
    if (a == b || b == c || a == c) continue;
    indices.insert(indices.end(), {a, b, c});
    if (!mesh.triangle_part.empty()) parts.push_back(mesh.triangle_part[t]);
  }
  return compact_vertices(welded, std::move(indices), std::move(parts));
}

// Exact values at multiples of 90 degrees keep axis-aligned rotations free of 1e-17 residue.
std::pair<double, double> cos_sin_deg(double deg) {
  const double q = deg / 90.0;
  if (q == std::round(q) && std::abs(q) < 1e15) {
    const auto k = static_cast<long long>(std::round(q));
    static constexpr double kCos[4] = {1, 0, -1, 0};
    static constexpr double kSin[4] = {0, 1, 0, -1};
    const auto i = static_cast<std::size_t>(((k % 4) + 4) % 4);
    return {kCos[i], kSin[i]};
  }
  const double r = deg * kPi / 180.0;
  return {std::cos(r), std::sin(r)};
}

}  // namespace

Mesh weld_vertices(const Mesh& mesh, WeldKey key) {
  Mesh out = weld_core(mesh, key);
  if (!mesh.normals.empty() || !mesh.tangents.empty()) compute_smooth_normals(out);
  if (!mesh.tangents.empty()) compute_tangents(out);
  return out;
}

Mesh decimate_to_vertex_count(const Mesh& mesh, std::size_t target_vertices, double tolerance) {
  if (target_vertices < 4)
    throw ParameterError(fmt::format(
        "cannot decimate to {} vertices: the target must be at least 4", target_vertices));
  if (target_vertices > mesh.vertex_count())
    throw ParameterError(
        fmt::format("cannot decimate a mesh of {} vertices up to {} (subdivide, or use "
                    "resample_to_vertex_count)",
                    mesh.vertex_count(), target_vertices));
  if (!(tolerance >= 0.0))
    throw ParameterError(fmt::format("decimation tolerance {} must be >= 0", tolerance));
  const double allowed = tolerance * static_cast<double>(target_vertices);

  Mesh work = weld_core(mesh, WeldKey::kPositionAndUv);
  const std::vector<std::uint16_t> part_of = split_vertices_by_part(work);
  if (work.vertex_count() <= target_vertices) {
    if (static_cast<double>(target_vertices - work.vertex_count()) > allowed)
      log_warn("welding left {} vertices, below the decimation target {}", work.vertex_count(),
               target_vertices);
    finish_attributes(work);
    return work;
  }

  Simplified s = search_target(work, target_vertices, /*sloppy=*/false);
  if (static_cast<double>(diff(s.vertices, target_vertices)) > allowed) {
    Simplified sloppy = search_target(work, target_vertices, /*sloppy=*/true);
    log_warn(
        "meshopt_simplify reached {} vertices, not {} (locked borders or topology); "
        "meshopt_simplifySloppy reached {}{}",
        s.vertices, target_vertices, sloppy.vertices,
        diff(sloppy.vertices, target_vertices) < diff(s.vertices, target_vertices) ? " and is used"
                                                                                   : "");
    if (diff(sloppy.vertices, target_vertices) < diff(s.vertices, target_vertices))
      s = std::move(sloppy);
  }
  if (static_cast<double>(diff(s.vertices, target_vertices)) > allowed)
    throw ParameterError(
        fmt::format("cannot decimate {} vertices to {} within {:.2g}%: the closest "
                    "simplification has {}",
                    work.vertex_count(), target_vertices, 100.0 * tolerance, s.vertices));

  std::vector<std::uint16_t> parts;
  if (!work.triangle_part.empty()) {
    parts.reserve(s.indices.size() / 3);
    for (std::size_t t = 0; t < s.indices.size() / 3; ++t)
      parts.push_back(part_of[s.indices[3 * t]]);
  }
  Mesh out = compact_vertices(work, std::move(s.indices), std::move(parts));
  finish_attributes(out);
  return out;
}

namespace {

/// subdivide() without the normals and tangents (resampling computes them once at the end).
Mesh subdivide_core(const Mesh& mesh, bool smooth) {
  const std::size_t V = mesh.vertex_count();
  const std::size_t T = mesh.triangle_count();
  for (std::uint32_t i : mesh.indices)
    PRT_CHECK(i < V, "subdivide: index {} out of range ({} vertices)", i, V);
  PRT_CHECK(V + 3 * T <= kNone, "subdivide: the result would exceed 32-bit indices");

  Mesh out;
  out.positions = mesh.positions;
  out.uvs = mesh.uvs;
  out.positions.reserve(V + 3 * T / 2 + 16);
  if (mesh.has_uvs()) out.uvs.reserve(out.positions.capacity());
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edge_ends;  // of every new vertex
  std::unordered_map<std::uint64_t, std::uint32_t> midpoint_of;
  midpoint_of.reserve(3 * T / 2 + 16);
  const auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
    const auto [it, inserted] = midpoint_of.try_emplace(edge_key(a, b), 0);
    if (inserted) {
      it->second = static_cast<std::uint32_t>(out.positions.size());
      out.positions.push_back(0.5f * (mesh.positions[a] + mesh.positions[b]));
      if (mesh.has_uvs()) out.uvs.push_back(0.5f * (mesh.uvs[a] + mesh.uvs[b]));
      edge_ends.emplace_back(a, b);
    }
    return it->second;
  };
  out.indices.reserve(12 * T);
  if (!mesh.triangle_part.empty()) out.triangle_part.reserve(4 * T);
  for (std::size_t t = 0; t < T; ++t) {
    const std::uint32_t a = mesh.indices[3 * t], b = mesh.indices[3 * t + 1],
                        c = mesh.indices[3 * t + 2];
    const std::uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
    out.indices.insert(out.indices.end(), {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca});
    if (!mesh.triangle_part.empty())
      out.triangle_part.insert(out.triangle_part.end(), 4, mesh.triangle_part[t]);
  }

  if (smooth) {
    // Loop's rules on the topology of positions: copies of a vertex (UV seams) move together.
    const std::vector<std::uint32_t> rep = position_representatives(mesh);
    struct EdgeInfo {
      std::uint32_t count = 0;
      std::uint32_t opposite[2] = {0, 0};
    };
    std::unordered_map<std::uint64_t, EdgeInfo> edges;
    edges.reserve(3 * T / 2 + 16);
    for (std::size_t t = 0; t < T; ++t) {
      const std::uint32_t r[3] = {rep[mesh.indices[3 * t]], rep[mesh.indices[3 * t + 1]],
                                  rep[mesh.indices[3 * t + 2]]};
      if (r[0] == r[1] || r[1] == r[2] || r[0] == r[2]) continue;
      for (int k = 0; k < 3; ++k) {
        EdgeInfo& e = edges[edge_key(r[k], r[(k + 1) % 3])];
        if (e.count < 2) e.opposite[e.count] = r[(k + 2) % 3];
        ++e.count;
      }
    }
    const auto P = [&](std::uint32_t v) { return Vec3d(mesh.positions[v]); };

    for (std::size_t k = 0; k < edge_ends.size(); ++k) {
      const std::uint32_t ra = rep[edge_ends[k].first], rb = rep[edge_ends[k].second];
      if (ra == rb) continue;
      const auto it = edges.find(edge_key(ra, rb));
      if (it == edges.end() || it->second.count != 2) continue;  // boundary edge: midpoint
      const EdgeInfo& e = it->second;
      out.positions[V + k] =
          Vec3(0.375 * (P(ra) + P(rb)) + 0.125 * (P(e.opposite[0]) + P(e.opposite[1])));
    }

    std::vector<std::vector<std::uint32_t>> neighbours(V), border(V);
    std::vector<std::uint8_t> non_manifold(V, 0);
    for (const auto& [key, e] : edges) {
      const auto a = static_cast<std::uint32_t>(key >> 32), b = static_cast<std::uint32_t>(key);
      neighbours[a].push_back(b);
      neighbours[b].push_back(a);
      if (e.count == 1) {
        border[a].push_back(b);
        border[b].push_back(a);
      } else if (e.count > 2) {
        non_manifold[a] = non_manifold[b] = 1;
      }
    }
    // Sum in index order: the result must not depend on the hash map's iteration order.
    for (auto& n : neighbours) std::sort(n.begin(), n.end());
    std::vector<Vec3> moved(V);
    for (std::size_t v = 0; v < V; ++v) {
      if (rep[v] != v) continue;
      const Vec3d p = P(static_cast<std::uint32_t>(v));
      Vec3d q = p;
      const std::size_t n = neighbours[v].size();
      if (non_manifold[v] || n < 2) {
        // fixed
      } else if (border[v].empty()) {
        const double w = 0.375 + 0.25 * std::cos(kTwoPi / static_cast<double>(n));
        const double beta = (0.625 - w * w) / static_cast<double>(n);
        Vec3d sum(0.0);
        for (std::uint32_t u : neighbours[v]) sum += P(u);
        q = (1.0 - static_cast<double>(n) * beta) * p + beta * sum;
      } else if (border[v].size() == 2) {
        const Vec3d b0 = P(std::min(border[v][0], border[v][1]));
        const Vec3d b1 = P(std::max(border[v][0], border[v][1]));
        const Vec3d d0 = p - b0, d1 = b1 - p;
        const double len = glm::length(d0) * glm::length(d1);
        const bool corner = !(len > 0.0) || glm::dot(d0, d1) < std::cos(kPi / 6.0) * len;
        // With b0 and b1 swapped the test reads the same: it measures the turn at v.
        if (!corner) q = 0.75 * p + 0.125 * (b0 + b1);
      }
      moved[v] = Vec3(q);
    }
    for (std::size_t v = 0; v < V; ++v) out.positions[v] = moved[rep[v]];
  }
  return out;
}

}  // namespace

Mesh subdivide(const Mesh& mesh, bool smooth) {
  Mesh out = subdivide_core(mesh, smooth);
  finish_attributes(out);
  return out;
}

Mesh resample_to_vertex_count(const Mesh& mesh, std::size_t target_vertices, double tolerance,
                              bool smooth) {
  if (target_vertices == mesh.vertex_count()) {
    Mesh out = mesh;
    finish_attributes(out);
    return out;
  }
  if (target_vertices < mesh.vertex_count())
    return decimate_to_vertex_count(mesh, target_vertices, tolerance);
  if (mesh.triangle_count() == 0)
    throw ParameterError("cannot resample a mesh without triangles to more vertices");
  Mesh fine = subdivide_core(mesh, smooth);
  while (fine.vertex_count() < target_vertices) fine = subdivide_core(fine, smooth);
  if (fine.vertex_count() == target_vertices) {
    finish_attributes(fine);
    return fine;
  }
  return decimate_to_vertex_count(fine, target_vertices, tolerance);
}

Mat3d Transform::linear() const {
  const auto [cx, sx] = cos_sin_deg(rotate_deg.x);
  const auto [cy, sy] = cos_sin_deg(rotate_deg.y);
  const auto [cz, sz] = cos_sin_deg(rotate_deg.z);
  // glm is column-major: m[column][row].
  Mat3d rx(1.0), ry(1.0), rz(1.0), s(0.0);
  rx[1][1] = cx, rx[1][2] = sx, rx[2][1] = -sx, rx[2][2] = cx;
  ry[0][0] = cy, ry[0][2] = -sy, ry[2][0] = sy, ry[2][2] = cy;
  rz[0][0] = cz, rz[0][1] = sz, rz[1][0] = -sz, rz[1][1] = cz;
  s[0][0] = scale.x, s[1][1] = scale.y, s[2][2] = scale.z;
  return rz * ry * rx * s;
}

void apply_transform(Mesh& mesh, const Transform& xf) {
  const Mat3d m = xf.linear();
  const double det = glm::determinant(m);
  if (!(std::abs(det) > 0.0) || !std::isfinite(det))
    throw ParameterError(fmt::format("transform is singular (scale [{}, {}, {}])", xf.scale.x,
                                     xf.scale.y, xf.scale.z));
  const Mat3d normal_matrix = glm::transpose(glm::inverse(m));
  for (Vec3& p : mesh.positions) p = Vec3(m * Vec3d(p) + xf.translate);
  for (Vec3& n : mesh.normals) {
    const Vec3d t = normal_matrix * Vec3d(n);
    const double len = glm::length(t);
    if (len > 0.0) n = Vec3(t / len);
  }
  for (std::size_t v = 0; v < mesh.tangents.size(); ++v) {
    const Vec3d t = m * Vec3d(mesh.tangents[v]);
    if (v < mesh.normals.size()) {
      const Vec3d n(mesh.normals[v]);
      mesh.tangents[v] = Vec3(t == Vec3d(0.0) ? LocalFrame::from_normal(n).t
                                              : LocalFrame::from_normal_tangent(n, t).t);
    } else {
      const double len = glm::length(t);
      if (len > 0.0) mesh.tangents[v] = Vec3(t / len);
    }
  }
  if (det < 0.0)
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
      std::swap(mesh.indices[3 * t + 1], mesh.indices[3 * t + 2]);
}

void normalize_to_unit_box(Mesh& mesh, bool on_ground) {
  if (mesh.positions.empty()) return;
  normalize_to_unit_box(mesh, on_ground, mesh.bounds());
}

void normalize_to_unit_box(Mesh& mesh, bool on_ground, const Aabb& box) {
  const Vec3d lo(box.lo), hi(box.hi);
  const Vec3d extent = hi - lo;
  const double largest = std::max({extent.x, extent.y, extent.z});
  if (!(largest > 0.0) || !std::isfinite(largest))
    throw ParameterError("cannot normalise a mesh of zero extent into the unit box");
  const double s = 1.0 / largest;
  const Vec3d centre = 0.5 * (lo + hi);
  for (Vec3& p : mesh.positions) {
    Vec3d q = (Vec3d(p) - centre) * s;
    if (on_ground) q.y = (static_cast<double>(p.y) - lo.y) * s;
    p = Vec3(q);
  }
}

Mesh select_parts(const Mesh& mesh, std::span<const std::uint16_t> parts) {
  std::vector<std::uint8_t> wanted;
  for (std::uint16_t p : parts) {
    if (p >= wanted.size()) wanted.resize(std::size_t{p} + 1, 0);
    wanted[p] = 1;
  }
  std::vector<std::uint32_t> indices;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const std::uint16_t p = mesh.part_of(t);
    if (p < wanted.size() && wanted[p])
      indices.insert(indices.end(), mesh.indices.begin() + static_cast<std::ptrdiff_t>(3 * t),
                     mesh.indices.begin() + static_cast<std::ptrdiff_t>(3 * t + 3));
  }
  return compact_vertices(mesh, std::move(indices), {});
}

std::size_t orient_consistently(Mesh& mesh) {
  const std::size_t T = mesh.triangle_count();
  if (T == 0) return 0;
  // Seam copies of a vertex are one vertex here: a UV seam must not cut a component in two.
  const std::vector<std::uint32_t> rep = position_representatives(mesh);
  const auto corner = [&](std::size_t t, int c) {
    return rep[mesh.indices[3 * t + static_cast<std::size_t>(c)]];
  };
  struct EdgeUse {
    std::uint32_t count = 0;
    std::uint32_t triangle[2] = {0, 0};
    bool forward[2] = {false, false};  ///< the triangle runs the edge from its lower end
  };
  std::unordered_map<std::uint64_t, EdgeUse> edges;
  edges.reserve(3 * T / 2 + 16);
  for (std::size_t t = 0; t < T; ++t) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = corner(t, k), b = corner(t, (k + 1) % 3);
      if (a == b) continue;
      EdgeUse& e = edges[edge_key(a, b)];
      if (e.count < 2) {
        e.triangle[e.count] = static_cast<std::uint32_t>(t);
        e.forward[e.count] = a < b;
      }
      ++e.count;
    }
  }
  const auto area = [&](std::size_t t) {
    const Vec3d a(mesh.positions[mesh.indices[3 * t]]);
    return glm::length(glm::cross(Vec3d(mesh.positions[mesh.indices[3 * t + 1]]) - a,
                                  Vec3d(mesh.positions[mesh.indices[3 * t + 2]]) - a));
  };
  const auto signed_volume = [&](std::size_t t) {
    return glm::dot(Vec3d(mesh.positions[mesh.indices[3 * t]]),
                    glm::cross(Vec3d(mesh.positions[mesh.indices[3 * t + 1]]),
                               Vec3d(mesh.positions[mesh.indices[3 * t + 2]])));
  };

  std::vector<std::int8_t> flip(T, -1);  // -1: not reached yet
  std::vector<std::uint32_t> component, stack;
  std::size_t flipped = 0;
  for (std::size_t seed = 0; seed < T; ++seed) {
    if (flip[seed] >= 0) continue;
    // Grow the component over manifold edges only: across an edge of three or more triangles
    // "consistent" has no meaning, and a boundary edge has no neighbour.
    component.clear();
    stack.assign(1, static_cast<std::uint32_t>(seed));
    flip[seed] = 0;
    bool closed = true;
    while (!stack.empty()) {
      const std::uint32_t t = stack.back();
      stack.pop_back();
      component.push_back(t);
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = corner(t, k), b = corner(t, (k + 1) % 3);
        if (a == b) continue;
        const EdgeUse& e = edges.at(edge_key(a, b));
        if (e.count != 2) {
          closed = false;
          continue;
        }
        const int self = e.triangle[0] == t ? 0 : 1;
        const std::uint32_t u = e.triangle[1 - self];
        // Consistent neighbours run their shared edge in opposite directions.
        const bool same_direction = e.forward[0] == e.forward[1];
        const auto want = static_cast<std::int8_t>(flip[t] ^ (same_direction ? 1 : 0));
        if (flip[u] < 0) {
          flip[u] = want;
          stack.push_back(u);
        }
        // A conflict (a non-orientable surface) keeps the first assignment.
      }
    }
    // Keep the orientation most of the component's area already has; a closed component must
    // then enclose positive volume (face outwards).
    double keep = 0.0, change = 0.0, volume = 0.0;
    for (std::uint32_t t : component) {
      (flip[t] ? change : keep) += area(t);
      volume += flip[t] ? -signed_volume(t) : signed_volume(t);
    }
    bool invert = change > keep;
    if (closed && (invert ? -volume : volume) < 0.0) invert = !invert;
    for (std::uint32_t t : component) {
      if (invert) flip[t] = static_cast<std::int8_t>(1 - flip[t]);
      if (flip[t]) {
        std::swap(mesh.indices[3 * t + 1], mesh.indices[3 * t + 2]);
        ++flipped;
      }
    }
  }
  if (flipped > 0) {
    if (!mesh.normals.empty()) compute_smooth_normals(mesh);
    if (!mesh.tangents.empty()) compute_tangents(mesh);
  }
  return flipped;
}

}  // namespace prt
