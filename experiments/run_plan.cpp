#include "run_plan.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "prtlab/base/error.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/geometry/scene.h"

namespace prt::experiments {
namespace {

constexpr std::size_t kMax = std::numeric_limits<std::size_t>::max();
// The vertex count the cost hints are given for: the bunny of the central paper's Table I.
constexpr double kHintVertices = 3286;

std::size_t mul(std::size_t a, std::size_t b) {
  if (a != 0 && b > kMax / a) return kMax;
  return a * b;
}
std::size_t add(std::size_t a, std::size_t b) {
  return b > kMax - a ? kMax : a + b;
}

std::size_t backend_points(const ExperimentSpec& spec, const std::string& backend) {
  if (spec.kind == ExperimentKind::kEqualStorage) return 1;
  if (const auto p = spec.points.find(backend); p != spec.points.end()) return p->second.size();
  if (const auto g = spec.grid.find(backend); g != spec.grid.end()) {
    std::size_t n = 1;
    for (const auto& [key, values] : g->second) n = mul(n, values.size());
    return n;
  }
  const auto& entry = CompressorRegistry::instance().get(backend);
  const bool fixed = spec.params.contains(backend) && entry.size_knob &&
                     spec.params.at(backend).contains(entry.size_knob->key);
  if (!entry.size_knob || fixed) return 1;
  return static_cast<std::size_t>(spec.knob_points);
}

std::size_t scene_grid_combinations(const ExperimentSpec& spec) {
  std::size_t n = 1;
  for (const auto& [key, values] : spec.scene_grid) n = mul(n, values.size());
  return n;
}

std::string duration(double s) {
  if (s < 60) return fmt::format("{:.0f} s", s);
  if (s < 3600) return fmt::format("{:.0f} min", s / 60);
  return fmt::format("{:.1f} h", s / 3600);
}

}  // namespace

std::size_t points_per_scene(const ExperimentSpec& spec) {
  std::size_t n = 0;
  for (const auto& b : spec.backends) n = add(n, backend_points(spec, b));
  return n;
}

std::size_t planned_points(const ExperimentSpec& spec) {
  return mul(mul(spec.scenes.size(), scene_grid_combinations(spec)), points_per_scene(spec));
}

void check_point_budget(const ExperimentSpec& spec, std::size_t max_points) {
  const std::size_t n = planned_points(spec);
  if (n <= max_points) return;
  std::string per_backend;
  for (const auto& b : spec.backends)
    per_backend +=
        fmt::format("{}{} {}", per_backend.empty() ? "" : ", ", b, backend_points(spec, b));
  throw InputError(
      spec.file,
      fmt::format("{} points ({} scene{} x {} scene-grid combination{} x {} a scene: "
                  "{}), more than --max-points {}; shrink the grid or raise "
                  "--max-points",
                  n == kMax ? std::string("more than 2^64") : std::to_string(n), spec.scenes.size(),
                  spec.scenes.size() == 1 ? "" : "s", scene_grid_combinations(spec),
                  scene_grid_combinations(spec) == 1 ? "" : "s", points_per_scene(spec),
                  per_backend, max_points));
}

RunPlan plan_run(const ExperimentSpec& spec, std::span<const SceneVariant> variants) {
  RunPlan plan;
  const auto& registry = CompressorRegistry::instance();
  for (const auto& variant : variants) {
    const SceneDesc desc = parse_scene(variant.file);
    const double scale =
        desc.target_vertices ? static_cast<double>(*desc.target_vertices) / kHintVertices : 1.0;
    for (const auto& b : spec.backends) {
      const std::size_t n = backend_points(spec, b);
      plan.points = add(plan.points, n);
      const double hint = registry.get(b).cost_hint_seconds;
      if (hint > 0)
        plan.estimated_seconds += static_cast<double>(n) * hint * scale;
      else if (std::ranges::count(plan.backends_without_hint, b) == 0)
        plan.backends_without_hint.push_back(b);
    }
  }
  return plan;
}

std::string RunPlan::summary() const {
  std::string out = fmt::format("{} point{}", points, points == 1 ? "" : "s");
  if (estimated_seconds > 0)
    out += fmt::format(", about {} from the backends' cost hints", duration(estimated_seconds));
  if (!backends_without_hint.empty()) {
    std::string list;
    for (const auto& b : backends_without_hint) list += (list.empty() ? "" : ", ") + b;
    out += fmt::format(" ({}: no cost hint)", list);
  }
  return out;
}

}  // namespace prt::experiments
