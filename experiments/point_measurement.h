#pragma once
// One point of an experiment: a backend at one set of parameters on one scene variant,
// measured as every report prints it (docs/experiments.md "Points"), and cached.
//
// A point is a stage of its own ("experiment-point" in the stage cache) keyed by the scene's
// transfer key, the backend, its canonical parameters and version, the evaluation settings
// (environments, views, image size, repeats, what is measured, the device) and the build, so
// an interrupted run resumes from the points it finished, a later run recomputes only points
// whose inputs changed, and a distributed runner can split points across machines without
// changing any number. Its record is a JSON object of fixed keys (point_record_columns());
// its images, when kept, are float sections of the same archive.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiment_spec.h"
#include "prtlab/image/image_io.h"
#include "prtlab/storage/stage_cache.h"
#include "scene_bench.h"

namespace prt::experiments {

struct PointOutcome {
  nlohmann::json record;         ///< point_record_columns() keys, plus "errors" (per env x view)
  std::vector<RgbImage> images;  ///< [view * lights + light] when kept, else empty
  bool cache_hit = false;
  double seconds = 0;  ///< this call
};

/// Measure `backend` at `params` (validated; canonicalised) on the bench, or load the point
/// from the cache. `keep_images` stores the rendered images with the point.
PointOutcome measure_point(const SceneBench& bench, const ExperimentSpec& spec,
                           const std::string& backend,
                           const std::map<std::string, std::string>& params, bool keep_images,
                           StageCache& cache, const BenchOptions& options);

/// The columns of points.csv, in order: every record has exactly these keys (null where a
/// value does not apply). "backend_metrics" is an object {name: value} of what the backend
/// measured of itself (CompressedTransfer::backend_metrics(); a JSON cell in points.csv), with
/// "backend_metric_meanings" {name: meaning} beside it in the record.
const std::vector<std::string>& point_record_columns();
/// The columns of errors.csv (one row per point, environment and view).
const std::vector<std::string>& error_record_columns();

}  // namespace prt::experiments
