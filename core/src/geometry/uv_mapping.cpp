#include "prtlab/geometry/uv_mapping.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <queue>
#include <unordered_map>

#include "prtlab/base/error.h"

namespace prt {
namespace {

constexpr std::uint32_t kUnassigned = std::numeric_limits<std::uint32_t>::max();
/// Weight of the irregularity term in the merge cost (the normal-spread term is in [0, 1]).
constexpr double kShapeWeight = 0.1;
/// Edges where the normals turn by more than this (60 degrees) are creases: they separate
/// charts (no adjacency across them), so no chart folds over a box's edge.
constexpr double kCosCrease = 0.5;

struct Faces {
  std::vector<Vec3d> normal;  ///< unit; zero for degenerate triangles
  std::vector<Vec3d> smooth;  ///< unit, smoothed over neighbours (chart classification)
  std::vector<double> area;
  std::vector<double> perimeter;
  std::vector<std::uint32_t> adj_begin;  ///< CSR over edge-adjacent triangles
  std::vector<std::uint32_t> adj;
  std::vector<double> adj_len;             ///< length of the shared edge, beside adj
  std::vector<std::uint32_t> touch_begin;  ///< CSR over all edge neighbours, creases included
  std::vector<std::uint32_t> touch;
};

Faces face_data(const Mesh& mesh) {
  const std::size_t T = mesh.triangle_count();
  Faces f;
  f.normal.resize(T);
  f.area.resize(T);
  f.perimeter.resize(T);
  for (std::size_t t = 0; t < T; ++t) {
    const Vec3d p0(mesh.positions[mesh.indices[3 * t]]);
    const Vec3d p1(mesh.positions[mesh.indices[3 * t + 1]]);
    const Vec3d p2(mesh.positions[mesh.indices[3 * t + 2]]);
    const Vec3d c = glm::cross(p1 - p0, p2 - p0);
    const double len = glm::length(c);
    f.area[t] = 0.5 * len;
    f.perimeter[t] = glm::length(p1 - p0) + glm::length(p2 - p1) + glm::length(p0 - p2);
    f.normal[t] = len > 0 && std::isfinite(len) ? c / len : Vec3d(0.0);
  }
  // Adjacency on the topology of positions, so that vertices already split in the input (seams
  // of another mapping, hard edges) do not cut charts.
  const std::vector<std::uint32_t> rep = position_representatives(mesh);
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> edges;
  edges.reserve(3 * T / 2 + 1);
  for (std::size_t t = 0; t < T; ++t) {
    for (int k = 0; k < 3; ++k) {
      std::uint32_t a = rep[mesh.indices[3 * t + k]], b = rep[mesh.indices[3 * t + (k + 1) % 3]];
      if (a == b) continue;
      if (a > b) std::swap(a, b);
      edges[(std::uint64_t{a} << 32) | b].push_back(static_cast<std::uint32_t>(t));
    }
  }
  // Creases (box edges) are not adjacencies: no chart grows, merges or smooths across one.
  const auto crease = [&](std::uint32_t s, std::uint32_t t) {
    const bool degenerate = f.normal[s] == Vec3d(0.0) || f.normal[t] == Vec3d(0.0);
    return !degenerate && glm::dot(f.normal[s], f.normal[t]) < kCosCrease;
  };
  std::vector<std::vector<std::pair<std::uint32_t, double>>> nb(T);
  std::vector<std::vector<std::uint32_t>> all(T);
  for (const auto& [key, tris] : edges) {
    const double len =
        glm::length(Vec3d(mesh.positions[key >> 32]) - Vec3d(mesh.positions[key & 0xFFFFFFFFu]));
    for (std::uint32_t s : tris)
      for (std::uint32_t t : tris) {
        if (s == t) continue;
        all[s].push_back(t);
        if (!crease(s, t)) nb[s].emplace_back(t, len);
      }
  }
  f.touch_begin.resize(T + 1, 0);
  for (std::size_t t = 0; t < T; ++t) {
    std::sort(all[t].begin(), all[t].end());
    f.touch_begin[t + 1] = f.touch_begin[t] + static_cast<std::uint32_t>(all[t].size());
  }
  f.touch.reserve(f.touch_begin[T]);
  for (const auto& n : all) f.touch.insert(f.touch.end(), n.begin(), n.end());
  f.adj_begin.resize(T + 1, 0);
  for (std::size_t t = 0; t < T; ++t) {
    // Sorted, so that nothing depends on the hash map's iteration order.
    std::sort(nb[t].begin(), nb[t].end());
    f.adj_begin[t + 1] = f.adj_begin[t] + static_cast<std::uint32_t>(nb[t].size());
  }
  f.adj.reserve(f.adj_begin[T]);
  for (const auto& n : nb)
    for (const auto& [t, len] : n) {
      f.adj.push_back(t);
      f.adj_len.push_back(len);
    }
  return f;
}

/// Area-weighted averaging of face normals with their edge neighbours, `rounds` times: scan
/// noise and small bumps would otherwise split a smooth region into many small charts.
/// Creases are not adjacencies, so they stay sharp.
void smooth_normals(Faces& f, int rounds) {
  const std::size_t T = f.area.size();
  std::vector<Vec3d> cur(T), next(T);
  for (std::size_t t = 0; t < T; ++t) cur[t] = f.area[t] * f.normal[t];
  for (int r = 0; r < rounds; ++r) {
    for (std::size_t t = 0; t < T; ++t) {
      Vec3d sum = cur[t];
      int count = 1;
      for (std::uint32_t i = f.adj_begin[t]; i < f.adj_begin[t + 1]; ++i) {
        sum += cur[f.adj[i]];
        ++count;
      }
      next[t] = sum / static_cast<double>(count);
    }
    std::swap(cur, next);
  }
  f.smooth.resize(T);
  for (std::size_t t = 0; t < T; ++t) {
    const double len = glm::length(cur[t]);
    f.smooth[t] = len > 0 && std::isfinite(len) ? cur[t] / len : f.normal[t];
  }
}

struct Cones {
  double cos_soft;  ///< smoothed normal vs axis
  double cos_hard;  ///< true normal vs axis
};

struct Cluster {
  Vec3d soft_sum{0.0}, hard_sum{0.0};  ///< area-weighted sums of smoothed and true normals
  double area = 0;
  double perimeter = 0;
  std::uint32_t version = 0;
  bool alive = true;
  std::vector<std::uint32_t> members;                ///< triangles
  std::unordered_map<std::uint32_t, double> border;  ///< neighbour -> shared edge length
};

/// Smallest cosine between the members' normals and the normalised sums' directions (soft:
/// smoothed normals, hard: true normals); degenerate triangles do not count.
std::pair<double, double> worst_cosines(const Faces& f, const Cluster& a, const Cluster& b) {
  const double ls = glm::length(a.soft_sum + b.soft_sum);
  const double lh = glm::length(a.hard_sum + b.hard_sum);
  // Both empty of area (degenerate triangles only): anything fits. Normals that cancel out (a
  // thin shell) fit no cone.
  if (a.area + b.area == 0) return {1.0, 1.0};
  if (!(ls > 0) || !(lh > 0)) return {-1.0, -1.0};
  const Vec3d ms = (a.soft_sum + b.soft_sum) / ls, mh = (a.hard_sum + b.hard_sum) / lh;
  double cs = 1.0, ch = 1.0;
  for (const Cluster* c : {&a, &b})
    for (std::uint32_t t : c->members) {
      if (f.normal[t] == Vec3d(0.0)) continue;
      cs = std::min(cs, glm::dot(f.smooth[t], ms));
      ch = std::min(ch, glm::dot(f.normal[t], mh));
    }
  return {cs, ch};
}

/// Bottom-up chart merging (in the spirit of Garland, Willmott and Heckbert 2001, "Hierarchical
/// face clustering"): every triangle starts as a chart; the adjacent pair whose union has the
/// smallest normal spread (the largest angle between a member's smoothed normal and the
/// union's mean, plus a small term favouring small charts so that flat regions grow evenly)
/// merges first, as long as every smoothed normal stays within the soft cone and every true
/// normal within the hard cone around the union's mean. Returns chart_of (dense ids) and each
/// chart's axis: its area-weighted mean true normal, which all its triangles are within
/// hard_cone of.
void cluster(const Faces& f, const Cones& k, std::vector<std::uint32_t>& chart_of,
             std::vector<Vec3d>& axes) {
  const std::size_t T = f.area.size();
  const double total = std::max(std::accumulate(f.area.begin(), f.area.end(), 0.0), 1e-300);
  std::vector<Cluster> c(T);
  for (std::uint32_t t = 0; t < T; ++t) {
    c[t].soft_sum = f.area[t] * f.smooth[t];
    c[t].hard_sum = f.area[t] * f.normal[t];
    c[t].area = f.area[t];
    c[t].members = {t};
    c[t].perimeter = f.perimeter[t];
    for (std::uint32_t i = f.adj_begin[t]; i < f.adj_begin[t + 1]; ++i)
      c[t].border[f.adj[i]] += f.adj_len[i];
  }
  struct Candidate {
    double cost;
    std::uint32_t a, b, va, vb;
    bool operator>(const Candidate& o) const {
      return cost != o.cost ? cost > o.cost : (a != o.a ? a > o.a : b > o.b);
    }
  };
  std::priority_queue<Candidate, std::vector<Candidate>, std::greater<>> queue;
  const double soft_range = 1.0 - k.cos_soft;
  const auto consider = [&](std::uint32_t a, std::uint32_t b) {
    if (a > b) std::swap(a, b);
    const auto [cs, ch] = worst_cosines(f, c[a], c[b]);
    if (cs < k.cos_soft || ch < k.cos_hard) return;
    // Irregularity P^2 / (4 pi A) (1 for a disc) keeps charts compact: ragged borders cost
    // seam vertices.
    const double area = c[a].area + c[b].area;
    const double perimeter = c[a].perimeter + c[b].perimeter - 2.0 * c[a].border.at(b);
    const double irregularity = area > 0 ? perimeter * perimeter / (4.0 * kPi * area) : 1.0;
    const double cost = (1.0 - cs) / soft_range + 0.25 * area / total + kShapeWeight * irregularity;
    queue.push({cost, a, b, c[a].version, c[b].version});
  };
  for (std::uint32_t t = 0; t < T; ++t)
    for (const auto& [n, len] : c[t].border)
      if (n > t) consider(t, n);
  while (!queue.empty()) {
    const Candidate m = queue.top();
    queue.pop();
    if (!c[m.a].alive || !c[m.b].alive || c[m.a].version != m.va || c[m.b].version != m.vb)
      continue;
    // Keep the larger cluster; fold the other into it.
    std::uint32_t keep = m.a, gone = m.b;
    if (c[keep].members.size() < c[gone].members.size()) std::swap(keep, gone);
    Cluster& kc = c[keep];
    Cluster& g = c[gone];
    kc.soft_sum += g.soft_sum;
    kc.hard_sum += g.hard_sum;
    kc.perimeter += g.perimeter - 2.0 * kc.border.at(gone);
    kc.area += g.area;
    kc.members.insert(kc.members.end(), g.members.begin(), g.members.end());
    kc.border.erase(gone);
    for (const auto& [n, len] : g.border) {
      if (n == keep) continue;
      kc.border[n] += len;
      auto& nb = c[n].border;
      nb.erase(gone);
      nb[keep] += len;
    }
    g = Cluster{};
    g.alive = false;
    ++kc.version;
    std::vector<std::uint32_t> around;
    around.reserve(kc.border.size());
    for (const auto& [n, len] : kc.border) around.push_back(n);
    std::sort(around.begin(), around.end());  // deterministic queue contents
    for (std::uint32_t n : around) consider(keep, n);
  }
  chart_of.assign(T, 0);
  axes.clear();
  for (std::uint32_t r = 0; r < T; ++r) {
    if (!c[r].alive) continue;
    const auto id = static_cast<std::uint32_t>(axes.size());
    const double len = glm::length(c[r].hard_sum);
    axes.push_back(len > 0 ? c[r].hard_sum / len : Vec3d(0, 0, 1));
    for (std::uint32_t t : c[r].members) chart_of[t] = id;
  }
}

/// Straightens chart borders: a triangle with at least two of its edge neighbours in another
/// chart moves there when it fits that chart's cones (soft: the chart's mean smoothed normal at
/// the start of the pass, hard: its fixed axis). Each move shortens the border by at least one
/// edge; a few passes remove most zigzags.
void smooth_borders(const Faces& f, const Cones& k, const std::vector<Vec3d>& axes,
                    std::vector<std::uint32_t>& chart_of, int passes) {
  const std::size_t T = chart_of.size(), C = axes.size();
  for (int pass = 0; pass < passes; ++pass) {
    std::vector<Vec3d> soft(C, Vec3d(0.0));
    for (std::size_t t = 0; t < T; ++t) soft[chart_of[t]] += f.area[t] * f.smooth[t];
    for (auto& v : soft) v = glm::length(v) > 0 ? glm::normalize(v) : v;
    std::size_t moved = 0;
    for (std::uint32_t t = 0; t < T; ++t) {
      const std::uint32_t a = chart_of[t];
      std::uint32_t best = kUnassigned;
      int best_count = 1;
      for (std::uint32_t i = f.adj_begin[t]; i < f.adj_begin[t + 1]; ++i) {
        const std::uint32_t b = chart_of[f.adj[i]];
        if (b == a) continue;
        int count = 0;
        for (std::uint32_t j = f.adj_begin[t]; j < f.adj_begin[t + 1]; ++j)
          count += chart_of[f.adj[j]] == b;
        if (count > best_count || (count == best_count && best != kUnassigned && b < best)) {
          best = b;
          best_count = count;
        }
      }
      if (best == kUnassigned) continue;
      int own = 0;
      for (std::uint32_t j = f.adj_begin[t]; j < f.adj_begin[t + 1]; ++j)
        own += chart_of[f.adj[j]] == a;
      if (own >= best_count) continue;
      if (f.normal[t] != Vec3d(0.0) && (glm::dot(f.smooth[t], soft[best]) < k.cos_soft ||
                                        glm::dot(f.normal[t], axes[best]) < k.cos_hard))
        continue;
      chart_of[t] = best;
      ++moved;
    }
    if (moved == 0) break;
  }
}

/// Charts smaller than `min_area` join the neighbouring chart whose axis fits all their
/// triangles best (smallest first; merged charts keep the receiver's axis, so the cones hold).
/// Neighbours across creases count here: scan noise leaves small islands behind sharp little
/// folds, while the hard cone still keeps a box's faces apart.
/// Returns the number of charts left; chart ids are renumbered densely.
std::size_t merge_small(const Faces& f, const Cones& k, double min_area, std::vector<Vec3d>& axes,
                        std::vector<std::uint32_t>& chart_of) {
  const std::size_t C = axes.size(), T = chart_of.size();
  std::vector<double> area(C, 0.0);
  std::vector<std::vector<std::uint32_t>> members(C);
  for (std::uint32_t t = 0; t < T; ++t) {
    area[chart_of[t]] += f.area[t];
    members[chart_of[t]].push_back(t);
  }
  std::vector<std::uint32_t> order(C);
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return area[a] < area[b]; });
  for (std::uint32_t c : order) {
    if (area[c] >= min_area || members[c].empty()) continue;
    std::vector<std::uint32_t> candidates;
    for (std::uint32_t t : members[c])
      for (std::uint32_t i = f.touch_begin[t]; i < f.touch_begin[t + 1]; ++i)
        if (chart_of[f.touch[i]] != c) candidates.push_back(chart_of[f.touch[i]]);
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    std::uint32_t into = kUnassigned;
    double into_worst = -2.0;
    for (std::uint32_t d : candidates) {
      // Only the hard cone: the soft one is what made these charts small in the first place.
      double worst = 2.0;
      for (std::uint32_t t : members[c])
        if (f.normal[t] != Vec3d(0.0)) worst = std::min(worst, glm::dot(f.normal[t], axes[d]));
      if (worst >= k.cos_hard && worst > into_worst) into_worst = worst, into = d;
    }
    if (into == kUnassigned) continue;
    for (std::uint32_t t : members[c]) chart_of[t] = into;
    members[into].insert(members[into].end(), members[c].begin(), members[c].end());
    members[c].clear();
    area[into] += area[c];
    area[c] = 0;
  }
  std::vector<std::uint32_t> renumber(C, kUnassigned);
  std::vector<Vec3d> kept;
  for (std::uint32_t c = 0; c < C; ++c) {
    if (members[c].empty()) continue;
    renumber[c] = static_cast<std::uint32_t>(kept.size());
    kept.push_back(axes[c]);
  }
  for (auto& c : chart_of) c = renumber[c];
  axes = std::move(kept);
  return axes.size();
}

}  // namespace

Vec2 planar_uv(const Vec3& position, const Vec3d& axis, const Vec3d& origin, double extent) {
  const Vec3d n = glm::normalize(axis);
  constexpr double kCosPolar = 0.90630778703665;  // cos(25 degrees)
  const Vec3d u = std::abs(n.y) < kCosPolar ? glm::normalize(glm::cross(Vec3d(0, 1, 0), n))
                                            : glm::normalize(Vec3d(1, 0, 0) - n.x * n);
  const Vec3d v = glm::cross(n, u);
  const Vec3d q = (Vec3d(position) - origin) / extent;
  return Vec2(static_cast<float>(glm::dot(q, u)), static_cast<float>(glm::dot(q, v)));
}

Mesh generate_uvs(const Mesh& mesh, const UvAtlasOptions& options, UvAtlasReport* report) {
  if (!(options.max_cone_deg > 0 && options.max_cone_deg <= 80))
    throw ParameterError(
        fmt::format("UV atlas: max_cone_deg = {} is outside (0, 80]", options.max_cone_deg));
  if (!(options.hard_cone_deg >= options.max_cone_deg && options.hard_cone_deg <= 85))
    throw ParameterError(fmt::format("UV atlas: hard_cone_deg = {} is outside [max_cone_deg, 85]",
                                     options.hard_cone_deg));
  if (!(options.min_chart_area >= 0 && options.min_chart_area < 1))
    throw ParameterError(
        fmt::format("UV atlas: min_chart_area = {} is outside [0, 1)", options.min_chart_area));
  const std::size_t T = mesh.triangle_count();
  const std::size_t V = mesh.vertex_count();
  for (std::uint32_t i : mesh.indices)
    PRT_CHECK(i < V, "generate_uvs: index {} out of range ({} vertices)", i, V);

  Faces f = face_data(mesh);
  const int rounds =
      options.smoothing_rounds >= 0
          ? options.smoothing_rounds
          : std::clamp(static_cast<int>(std::lround(std::sqrt(double(T)) / 25.0)), 1, 16);
  smooth_normals(f, rounds);
  const Cones cones{std::cos(options.max_cone_deg * kPi / 180.0),
                    std::cos(options.hard_cone_deg * kPi / 180.0)};
  std::vector<Vec3d> axes;
  std::vector<std::uint32_t> chart_of;
  cluster(f, cones, chart_of, axes);
  const double total_area = std::accumulate(f.area.begin(), f.area.end(), 0.0);
  merge_small(f, cones, options.min_chart_area * total_area, axes, chart_of);
  smooth_borders(f, cones, axes, chart_of, 8);
  const std::size_t C = axes.size();

  // The mean normal is the lower-stretch projection plane; keep the growth axis only where the
  // mean would push a triangle past the cone.
  {
    std::vector<Vec3d> sum(C, Vec3d(0.0));
    for (std::size_t t = 0; t < T; ++t) sum[chart_of[t]] += f.area[t] * f.normal[t];
    std::vector<Vec3d> mean(C);
    std::vector<std::uint8_t> ok(C, 1);
    for (std::size_t c = 0; c < C; ++c) {
      const double len = glm::length(sum[c]);
      if (len > 0)
        mean[c] = sum[c] / len;
      else
        ok[c] = 0;
    }
    for (std::size_t t = 0; t < T; ++t) {
      const std::uint32_t c = chart_of[t];
      if (ok[c] && f.normal[t] != Vec3d(0.0) && glm::dot(f.normal[t], mean[c]) < cones.cos_hard)
        ok[c] = 0;
    }
    for (std::size_t c = 0; c < C; ++c)
      if (ok[c]) axes[c] = mean[c];
  }

  const Aabb box = mesh.bounds();
  const Vec3d origin(box.lo);
  const Vec3 ext = box.extent();
  double extent = std::max({double(ext.x), double(ext.y), double(ext.z)});
  if (!(extent > 0)) extent = 1.0;

  Mesh out;
  const bool normals = mesh.normals.size() == V;
  std::unordered_map<std::uint64_t, std::uint32_t> copy_of;
  copy_of.reserve(V + V / 4);
  out.indices.resize(mesh.indices.size());
  double max_angle = 0;
  for (std::size_t t = 0; t < T; ++t) {
    const std::uint32_t c = chart_of[t];
    if (f.normal[t] != Vec3d(0.0))
      max_angle =
          std::max(max_angle, std::acos(std::clamp(glm::dot(f.normal[t], axes[c]), -1.0, 1.0)));
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh.indices[3 * t + k];
      const auto [it, inserted] = copy_of.try_emplace((std::uint64_t{v} << 32) | c, 0);
      if (inserted) {
        it->second = static_cast<std::uint32_t>(out.positions.size());
        out.positions.push_back(mesh.positions[v]);
        if (normals) out.normals.push_back(mesh.normals[v]);
        out.uvs.push_back(planar_uv(mesh.positions[v], axes[c], origin, extent));
      }
      out.indices[3 * t + k] = it->second;
    }
  }
  out.triangle_part = mesh.triangle_part;
  if (report) {
    // Border smoothing can empty a chart; count the ones in use.
    std::vector<std::uint8_t> used(C, 0);
    for (std::uint32_t c : chart_of) used[c] = 1;
    report->charts = static_cast<std::size_t>(std::count(used.begin(), used.end(), 1));
    report->input_vertices = V;
    report->output_vertices = out.vertex_count();
    report->max_angle_deg = max_angle * 180.0 / kPi;
  }
  return out;
}

UvStretch measure_uv_stretch(const Mesh& mesh, int part) {
  if (!mesh.has_uvs()) throw ParameterError("measure_uv_stretch: the mesh has no UVs");
  struct Tri {
    double area, ratio, aniso;
  };
  std::vector<Tri> tris;
  UvStretch s;
  double area3 = 0, area_uv = 0;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    if (part >= 0 && mesh.part_of(t) != part) continue;
    const std::uint32_t* i = &mesh.indices[3 * t];
    const Vec3d p0(mesh.positions[i[0]]);
    const Vec3d e1 = Vec3d(mesh.positions[i[1]]) - p0;
    const Vec3d e2 = Vec3d(mesh.positions[i[2]]) - p0;
    const Vec3d c = glm::cross(e1, e2);
    const double a = 0.5 * glm::length(c);
    const double l1 = glm::length(e1);
    if (!(a > 0) || !(l1 > 0)) continue;
    // The triangle in its own plane: P1 = (l1, 0), P2 = (x2, y2) with y2 > 0.
    const Vec3d xh = e1 / l1;
    const Vec3d yh = glm::cross(c / (2 * a), xh);
    const double x2 = glm::dot(e2, xh), y2 = glm::dot(e2, yh);
    const Vec2d w0(mesh.uvs[i[0]]);
    const Vec2d d1 = Vec2d(mesh.uvs[i[1]]) - w0, d2 = Vec2d(mesh.uvs[i[2]]) - w0;
    // J [l1 x2; 0 y2] = [d1 d2]  =>  J = [d1 d2] [1/l1, -x2/(l1 y2); 0, 1/y2].
    const double j00 = d1.x / l1, j10 = d1.y / l1;
    const double j01 = (d2.x - x2 * j00) / y2, j11 = (d2.y - x2 * j10) / y2;
    const double det = j00 * j11 - j01 * j10;
    // Singular values of a 2x2 matrix from its Frobenius norm and determinant.
    const double fro2 = j00 * j00 + j01 * j01 + j10 * j10 + j11 * j11;
    const double disc = std::sqrt(std::max(0.0, fro2 * fro2 - 4 * det * det));
    const double s1 = std::sqrt(0.5 * (fro2 + disc));
    const double s2 = std::sqrt(std::max(0.0, 0.5 * (fro2 - disc)));
    ++s.triangles;
    if (det < 0) ++s.flipped;
    if (det == 0) ++s.degenerate_uv;
    area3 += a;
    area_uv += std::abs(det) * a;
    tris.push_back({a, std::abs(det), s2 > 0 ? s1 / s2 : std::numeric_limits<double>::infinity()});
  }
  if (tris.empty() || !(area_uv > 0)) return s;
  const double g = area_uv / area3;
  std::sort(tris.begin(), tris.end(), [](const Tri& a, const Tri& b) { return a.ratio < b.ratio; });
  double mean = 0, aniso_sum = 0, aniso_area = 0;
  s.anisotropy_max = 0;
  for (auto& t : tris) {
    t.ratio /= g;
    mean += t.area * t.ratio;
    if (std::isfinite(t.aniso)) {
      aniso_sum += t.area * t.aniso;
      aniso_area += t.area;
    }
    s.anisotropy_max = std::max(s.anisotropy_max, t.aniso);
  }
  mean /= area3;  // 1 up to rounding
  double var = 0, cum = 0;
  bool have05 = false, have95 = false;
  for (const auto& t : tris) {
    var += t.area * (t.ratio - mean) * (t.ratio - mean);
    cum += t.area;
    if (!have05 && cum >= 0.05 * area3) s.area_ratio_p05 = t.ratio, have05 = true;
    if (!have95 && cum >= 0.95 * area3) s.area_ratio_p95 = t.ratio, have95 = true;
  }
  if (!have95) s.area_ratio_p95 = tris.back().ratio;
  s.area_ratio_min = tris.front().ratio;
  s.area_ratio_max = tris.back().ratio;
  s.area_ratio_std = std::sqrt(var / area3);
  s.anisotropy_mean = aniso_area > 0 ? aniso_sum / aniso_area : 0;
  return s;
}

}  // namespace prt
