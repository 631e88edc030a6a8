#pragma once
// How much an experiment file asks for, known before anything runs: the number of points
// (counted, never enumerated, so a 1000 x 1000 grid costs nothing to count) and an estimate of
// the time from the backends' cost hints (CompressorEntry::cost_hint_seconds). The CLI prints
// both before a run and refuses a file whose count exceeds --max-points.
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "experiment_spec.h"
#include "scene_variants.h"

namespace prt::experiments {

/// The default of --max-points: the repository's largest file (the full pareto grid) fits
/// with room; a typo such as a 1000-value list does not.
inline constexpr std::size_t kDefaultMaxPoints = 2000;

/// Points one scene (variant) of `spec` measures: per backend its explicit points, its grid's
/// combinations, its size-knob sweep (knob_points) or its one fixed point; 1 per backend for
/// equal storage. Saturates at SIZE_MAX instead of overflowing.
std::size_t points_per_scene(const ExperimentSpec& spec);
/// points_per_scene() times the scenes and the combinations of scene_grid.
std::size_t planned_points(const ExperimentSpec& spec);

/// InputError naming the file when planned_points(spec) > max_points: the count, what it is the
/// product of, and --max-points.
void check_point_budget(const ExperimentSpec& spec, std::size_t max_points);

struct RunPlan {
  std::size_t points = 0;
  /// Sum over points of the backend's cost hint scaled by the scene's vertex count relative to
  /// the 3,286 vertices the hints are given for; the points of backends without a hint are
  /// not in it.
  double estimated_seconds = 0;
  std::vector<std::string> backends_without_hint;
  /// "12 points, about 4 min from the backends' cost hints (coo: no cost hint)".
  std::string summary() const;
};

/// The plan of `spec` over its resolved scene variants (each scene file read for its
/// target_vertices; a scene without one counts as the hint's 3,286).
RunPlan plan_run(const ExperimentSpec& spec, std::span<const SceneVariant> variants);

}  // namespace prt::experiments
