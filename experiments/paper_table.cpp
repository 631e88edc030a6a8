#include "paper_table.h"

#include <fmt/format.h>

#include <map>

#include "prtlab/base/error.h"
#include "prtlab/compress/backend_evaluation.h"
#include "prtlab/compress/backend_input.h"
#include "prtlab/compress/compression_stage.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/geometry/scene.h"
#include "prtlab/storage/data_paths.h"
#include "prtlab/transfer/scene_transfer.h"

namespace prt::experiments {
namespace {

TimingPair timing_of(const BackendEvaluation& ev) {
  return {ev.ms_cpp, ev.ms_opencl, ev.opencl_vs_cpp};
}

class Reporter {
 public:
  Reporter(const TableOptions& o, PaperTable table, std::size_t count)
      : o_(o), table_(to_string(table)), count_(count) {}
  void operator()(std::size_t index, const std::string& scene, const std::string& what) const {
    if (o_.on_progress)
      o_.on_progress(fmt::format("[{} {}/{}] {}: {}", table_, index + 1, count_, scene, what));
  }

 private:
  const TableOptions& o_;
  std::string_view table_;
  std::size_t count_;
};

SceneRow measure_scene(const SceneDesc& desc, const TableOptions& o, StageCache& cache,
                       std::map<int, std::vector<EvaluationLight>>& lights_by_resolution,
                       const std::function<void(const std::string&)>& report) {
  const CacheMode mode = o.force ? CacheMode::kRefresh : CacheMode::kUse;
  SceneRow row;
  row.scene = desc.name;
  row.scene_file = desc.file;

  report("exact transfer T");
  PrepareOptions popt;
  popt.cache = mode;
  popt.show_progress = o.show_progress_bars;
  const std::vector<std::string> backends = {o.backend, o.reference};
  const PreparedScene scene = prepare_scene_for(desc, backends, cache, popt);
  const SceneTransfer& st = scene.transfer;
  const TransferMatrix& t = st.result.transfer;
  row.backend = o.backend;
  row.reference = o.reference;
  row.vertices = t.vertex_count();
  row.local_count = t.local_count();
  row.pixel_count = static_cast<int>(t.cols());
  row.supersampling = t.supersampling();
  row.nnz = t.nnz();
  row.nnz_millions = static_cast<double>(row.nnz) / 1e6;
  row.mflops = 2.0 * static_cast<double>(row.nnz) / 1e6;
  row.dense_bytes = t.dense_bytes();
  row.dense_mb = static_cast<double>(row.dense_bytes) / 1e6;
  row.transfer_seconds = st.result.stats.seconds_total;
  row.transfer_cache_hit = st.cache_hit;
  report(fmt::format("T has {} rows x {} columns, {:.2f} M non-zeros ({} in {:.2f} s)", t.rows(),
                     t.cols(), row.nnz_millions,
                     st.cache_hit ? "from the cache, computed" : "computed now",
                     row.transfer_seconds));

  const auto& registry = CompressorRegistry::instance();
  report(fmt::format("compression ({})", o.backend));
  const CompressionResult bic =
      compress_cached(o.backend, o.params, scene.input(registry.get(o.backend)), st.key, cache,
                      mode, o.show_progress_bars);
  const CompressionResult ref =
      compress_cached(o.reference, {}, scene.input(registry.get(o.reference)), st.key, cache, mode,
                      o.show_progress_bars);
  row.params = bic.params;
  row.compress_seconds = bic.compress_seconds;
  row.compress_cache_hit = bic.cache_hit;
  row.precompute_minutes = (row.transfer_seconds + row.compress_seconds) / 60.0;
  const StorageReport storage = bic.compressed->storage();
  row.storage = storage.components;
  row.reduced_bytes = storage.total_bytes();
  row.reduced_mb = static_cast<double>(row.reduced_bytes) / 1e6;
  row.data_percent =
      100.0 * static_cast<double>(row.reduced_bytes) / static_cast<double>(row.dense_bytes);
  row.reduced_mflops = bic.compressed->flops_per_relight() / 1e6;
  row.computation_percent = row.mflops > 0 ? 100.0 * row.reduced_mflops / row.mflops : 0.0;
  report(fmt::format(
      "{}: {:.2f} of {:.2f} MFLOPs ({:.1f} %), {:.1f} MB ({:.2f} %), {} in "
      "{:.2f} s",
      o.backend, row.reduced_mflops, row.mflops, row.computation_percent, row.reduced_mb,
      row.data_percent, bic.cache_hit ? "from the cache, computed" : "computed now",
      row.compress_seconds));

  auto& lights = lights_by_resolution[desc.cubemap_resolution];
  if (lights.empty()) lights = evaluation_lights(desc.cubemap_resolution, o.evaluation_lights);
  for (const auto& l : lights) row.evaluation_lights.push_back(l.name);
  report(fmt::format("relight timing ({} repeats) and error over {} lights", o.repeats,
                     lights.size()));
  const BackendEvaluation ev_bic =
      evaluate_backend(*bic.compressed, t, lights, o.device, {.repeats = o.repeats});
  const BackendEvaluation ev_ref =
      evaluate_backend(*ref.compressed, t, lights, o.device, {.repeats = o.repeats});
  row.subject = timing_of(ev_bic);
  row.reference_timing = timing_of(ev_ref);
  row.ms_project_light = ev_bic.ms_project;
  row.rel_l2_error_mean = ev_bic.mean_rel_l2;
  row.rel_l2_error_max = ev_bic.max_rel_l2;
  row.frobenius_rel_error = ev_bic.frobenius.relative;
  row.frobenius_rel_error_stderr = ev_bic.frobenius.standard_error;
  row.max_vertex_rel_error = ev_bic.max_vertex_rel;

  report("lossless check");
  LosslessOptions lossless = o.lossless;
  lossless.device = o.device;
  row.lossless = check_lossless(*bic.compressed, t, desc.cubemap_resolution, lossless);
  report(fmt::format("lossless: {} ({} probes, max count error {:.2g}; random lights {:.2g})",
                     row.lossless.verdict(), row.lossless.cpp.probes,
                     row.lossless.cpp.max_count_error, row.lossless.cpp.random_max_rel_error));
  return row;
}

}  // namespace

std::vector<SceneDesc> resolve_table_scenes(PaperTable table,
                                            const std::vector<std::string>& names) {
  const std::vector<std::string> list = names.empty() ? table_scenes(table) : names;
  if (list.empty()) throw ParameterError("no scenes to run");
  std::vector<SceneDesc> scenes;
  for (const auto& name : list) scenes.push_back(parse_scene(resolve_scene(name)));
  return scenes;
}

TableResult run_paper_table(PaperTable table, const TableOptions& o) {
  if (o.repeats < 1) throw ParameterError(fmt::format("repeats must be >= 1, not {}", o.repeats));
  if (o.evaluation_lights < 1 || o.evaluation_lights > 8)
    throw ParameterError(
        fmt::format("evaluation lights must be in 1..8, not {}", o.evaluation_lights));
  TableResult result;
  result.table = table;
  result.provenance = collect_provenance(o.command_line, o.device);

  // Validate everything cheap before the first expensive stage, so a typo costs nothing and
  // leaves nothing behind.
  const auto& entry = CompressorRegistry::instance().get(o.backend);
  (void)CompressorRegistry::instance().get(o.reference);
  const ParamSet validated(o.backend, entry.params, o.params);
  const std::vector<SceneDesc> scenes = resolve_table_scenes(table, o.scenes);
  std::vector<std::string> names;
  for (const auto& s : scenes) names.push_back(s.name);

  StageCache cache = o.cache_root ? StageCache(*o.cache_root) : StageCache();
  std::map<int, std::vector<EvaluationLight>> lights;
  const Reporter reporter(o, table, scenes.size());
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    const auto report = [&](const std::string& what) { reporter(i, scenes[i].name, what); };
    SceneRow row = measure_scene(scenes[i], o, cache, lights, report);
    row.paper = paper_row(table, row.scene);
    result.rows.push_back(std::move(row));
  }

  result.parameters = {
      {"backend", o.backend},
      {"backend_parameters", validated.canonical()},
      {"backend_version", entry.version},
      {"reference_backend", o.reference},
      {"repeats", o.repeats},
      {"evaluation_lights", o.evaluation_lights},
      {"lossless_random_lights", o.lossless.random_lights},
      {"lossless_seed", o.lossless.seed},
      {"force", o.force},
      {"stage_cache", cache.root().string()},
      {"scenes", names},
  };
  return result;
}

}  // namespace prt::experiments
