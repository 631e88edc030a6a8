#pragma once
// What the points of one scene variant share, built once per scene: the exact transfer and
// every backend's inputs, the mesh and materials, the cameras, the evaluation lights (the
// experiment's environments at the scene's cubemap resolution) and the reference backend's
// images, against which every point's images are compared.
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "experiment_spec.h"
#include "prtlab/compress/backend_evaluation.h"
#include "prtlab/compress/backend_input.h"
#include "prtlab/geometry/camera.h"
#include "prtlab/geometry/scene.h"
#include "prtlab/image/image_io.h"
#include "prtlab/render/btf_shading.h"
#include "prtlab/storage/stage_cache.h"
#include "scene_variants.h"

namespace prt {
class ClContext;
}

namespace prt::experiments {

/// Everything the points of one scene variant share, built once: T and every backend's
/// inputs, the mesh and materials, cameras, the evaluation lights and the exact images.
struct SceneBench {
  SceneVariant variant;
  PreparedScene prepared;
  Scene scene;
  ShadingMaterials materials;
  std::vector<std::string> view_names;
  std::vector<Camera> cameras;
  std::vector<EvaluationLight> lights;  ///< one per environment of the spec, in its order
  std::vector<Cubemap> fps_lights;      ///< the first environment rotated, for light-change frames
  /// The reference backend's images and hit masks, [view * lights + light].
  std::vector<RgbImage> exact_images;
  std::vector<std::vector<std::uint8_t>> masks;  ///< per view
  std::vector<double> exposure;  ///< [view * lights + light]: PNG exposure of the exact image
  nlohmann::json info;           ///< vertices, M, N, nnz, T's computation time
};

struct BenchOptions {
  ClContext* device = nullptr;
  CacheMode cache_mode = CacheMode::kUse;
  bool show_progress = false;
};

/// Build the bench of a scene variant for `spec` (stages from `cache`).
SceneBench prepare_bench(const SceneVariant& variant, const ExperimentSpec& spec, StageCache& cache,
                         const BenchOptions& options);

/// Exposure (stops) that maps the 99th-percentile luminance of the hit pixels to 0.9, so every
/// backend's PNG of a view uses the exact image's exposure and differences stay visible.
double exposure_of(const RgbImage& img, std::span<const std::uint8_t> mask);

/// The radiance cubemap of an environment of the spec at `resolution`, rotated about +y by
/// `rotate_deg` (a procedural sun turns its direction; an EXR turns its columns).
Cubemap environment_cubemap(const EnvironmentSpec& e, int resolution, double rotate_deg = 0);

/// Reads every environment map `spec` names (the sun environments need no file) so that a file
/// that exists but is not a readable map fails before any stage runs: an InputError naming the
/// experiment file, the environment and the map's problem.
void check_environments(const ExperimentSpec& spec);

}  // namespace prt::experiments
