#include "experiment_run.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <optional>
#include <set>

#include "pareto_front.h"
#include "point_measurement.h"
#include "provenance.h"
#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/base/named_warning.h"
#include "prtlab/base/statistics.h"
#include "prtlab/compress/compression_stage.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/light_options.h"
#include "prtlab/distributed/shared_work.h"
#include "prtlab/distributed/work_queue.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/render/image_error.h"
#include "prtlab/storage/atomic_file.h"
#include "result_images.h"
#include "result_tables.h"
#include "scene_variants.h"
#include "storage_search.h"

namespace prt::experiments {
namespace {
namespace fs = std::filesystem;
using json = nlohmann::json;

std::string format_knob(double v, bool integer) {
  return integer ? fmt::format("{}", static_cast<std::int64_t>(std::llround(v)))
                 : fmt::format("{}", v);
}

std::string duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  const auto s = static_cast<long long>(std::llround(seconds));
  if (s < 60) return fmt::format("{}s", s);
  if (s < 3600) return fmt::format("{}m{:02}s", s / 60, s % 60);
  return fmt::format("{}h{:02}m", s / 3600, (s / 60) % 60);
}

// Every combination of a backend's grid, over `fixed` (the spec's params of the backend).
std::vector<std::map<std::string, std::string>> grid_points(
    const std::map<std::string, std::vector<std::string>>& grid,
    const std::map<std::string, std::string>& fixed) {
  std::vector<std::map<std::string, std::string>> out = {fixed};
  for (const auto& [key, values] : grid) {
    std::vector<std::map<std::string, std::string>> next;
    for (const auto& p : out)
      for (const auto& v : values) {
        auto q = p;
        q[key] = v;
        next.push_back(std::move(q));
      }
    out = std::move(next);
  }
  return out;
}

bool knob_is_int(const CompressorEntry& e) {
  for (const auto& p : e.params)
    if (p.key == e.size_knob->key) return p.type == ParamType::kInt;
  return false;
}

// The points a sweep measures for one backend.
std::vector<std::map<std::string, std::string>> sweep_points(const ExperimentSpec& spec,
                                                             const std::string& backend) {
  const auto& entry = CompressorRegistry::instance().get(backend);
  const auto fixed = spec.params.contains(backend) ? spec.params.at(backend)
                                                   : std::map<std::string, std::string>{};
  if (spec.points.contains(backend)) {
    std::vector<std::map<std::string, std::string>> out;
    for (const auto& point : spec.points.at(backend)) {
      auto p = fixed;
      for (const auto& [k, v] : point) p[k] = v;
      out.push_back(std::move(p));
    }
    return out;
  }
  if (spec.grid.contains(backend)) return grid_points(spec.grid.at(backend), fixed);
  if (!entry.size_knob || fixed.contains(entry.size_knob->key)) return {fixed};
  std::vector<std::map<std::string, std::string>> out;
  const bool integer = knob_is_int(entry);
  for (double v : knob_values(*entry.size_knob, integer, spec.knob_points)) {
    auto p = fixed;
    p[entry.size_knob->key] = format_knob(v, integer);
    out.push_back(std::move(p));
  }
  return out;
}

double time_of(const json& r) {
  if (r["relight_ms_opencl"].is_number()) return r["relight_ms_opencl"].get<double>();
  if (r["relight_ms_cpp"].is_number()) return r["relight_ms_cpp"].get<double>();
  return NAN;
}
double number_or_nan(const json& v) {
  return v.is_number() ? v.get<double>() : NAN;
}

// Marks each point on its backend's fronts (per scene): run time and storage against L* error.
void mark_pareto(json& points) {
  std::map<std::pair<std::string, std::string>, std::vector<std::size_t>> groups;
  for (std::size_t i = 0; i < points.size(); ++i)
    groups[{points[i]["scene"], points[i]["backend"]}].push_back(i);
  for (const auto& [_, members] : groups) {
    std::vector<CostError> by_time, by_storage;
    for (std::size_t i : members) {
      const double err = number_or_nan(points[i]["lstar_rel_l2_mean"]);
      by_time.push_back({time_of(points[i]), err});
      by_storage.push_back({number_or_nan(points[i]["storage_bytes"]), err});
      points[i]["pareto_time"] = false;
      points[i]["pareto_storage"] = false;
    }
    for (std::size_t k : pareto_front(by_time)) points[members[k]]["pareto_time"] = true;
    for (std::size_t k : pareto_front(by_storage)) points[members[k]]["pareto_storage"] = true;
  }
}

// Files this runner writes into a result folder (removed by --force before a new run).
// The files a run wrote, relative to its folder (the manifest kept in .complete): the result
// files and every image its result names.
std::vector<std::string> written_files(const json& result) {
  std::vector<std::string> out = {"result.json", "points.csv", "errors.csv"};
  for (const auto& set : result.at("image_sets"))
    for (const auto& e : set.at("images")) out.push_back(e.at("exact").get<std::string>());
  for (const auto& p : result.at("points"))
    if (p.contains("images"))
      for (const auto& e : p.at("images")) {
        out.push_back(e.at("image").get<std::string>());
        out.push_back(e.at("error_map").get<std::string>());
      }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// The manifest of a complete run (empty for an older .complete without one).
std::vector<std::string> manifest_of(const fs::path& complete) {
  std::ifstream in(complete);
  const json j = json::parse(in, nullptr, false);
  std::vector<std::string> out;
  if (j.is_object() && j.contains("files") && j["files"].is_array())
    for (const auto& f : j["files"])
      if (f.is_string()) out.push_back(f.get<std::string>());
  return out;
}

// The label of a point in progress lines and failures: the backend, then its parameters.
std::string point_label(const std::string& backend,
                        const std::map<std::string, std::string>& params) {
  std::string desc;
  for (const auto& [k, v] : params) desc += fmt::format(" {}={}", k, v);
  return backend + desc;
}

// The storage an equal-storage experiment matches on a scene: a fixed size, or what the
// target backend stores there.
std::uint64_t storage_target(const ExperimentSpec& spec, const SceneBench& bench, StageCache& cache,
                             const BenchOptions& bo, bool show_progress) {
  if (spec.target.megabytes)
    return static_cast<std::uint64_t>(std::llround(*spec.target.megabytes * 1e6));
  const auto& te = CompressorRegistry::instance().get(spec.target.backend);
  const CompressionResult cr =
      compress_cached(spec.target.backend, spec.target.params, bench.prepared.input(te),
                      bench.prepared.transfer.key, cache, bo.cache_mode, show_progress);
  return cr.compressed->storage().total_bytes();
}

struct EqualStoragePoint {
  PointOutcome outcome;
  json search;
};

struct EqualStorageParams {
  std::map<std::string, std::string> params;  ///< the experiment's, the size knob's value found
  json search;
};

// One backend's parameters at the target storage: the search over its size knob (when the
// experiment leaves it free), each probe a compression through the stage cache.
// How a probe compresses: compress_cached, or compress_together in a distributed run's
// collective phase.
using CompressFn =
    std::function<CompressionResult(const std::map<std::string, std::string>& compression)>;

EqualStorageParams equal_storage_params(const ExperimentSpec& spec, const SceneBench& bench,
                                        const std::string& scene, const std::string& backend,
                                        std::uint64_t target, StageCache& cache,
                                        const BenchOptions& bo,
                                        const std::function<void(const std::string&)>& report,
                                        CompressFn compress = nullptr) {
  const auto& entry = CompressorRegistry::instance().get(backend);
  if (!compress)
    compress = [&](const std::map<std::string, std::string>& compression) {
      return compress_cached(backend, compression, bench.prepared.input(entry),
                             bench.prepared.transfer.key, cache, bo.cache_mode, bo.show_progress);
    };
  auto params = spec.params.contains(backend) ? spec.params.at(backend)
                                              : std::map<std::string, std::string>{};
  json search = {{"scene", scene}, {"backend", backend}, {"target_bytes", target}};
  if (entry.size_knob && !params.contains(entry.size_knob->key)) {
    const bool integer = knob_is_int(entry);
    const auto storage_at = [&](double v) {
      auto p = params;
      p[entry.size_knob->key] = format_knob(v, integer);
      report(fmt::format("{} {}: storage search, {} = {}", scene, backend, entry.size_knob->key,
                         p[entry.size_knob->key]));
      const CompressionResult cr = compress(split_point_params(entry, p).compression);
      return cr.compressed->storage().total_bytes();
    };
    const StorageSearch s =
        search_equal_storage(*entry.size_knob, integer, target, spec.target.tolerance,
                             spec.target.max_probes, storage_at);
    params[entry.size_knob->key] = format_knob(s.value, integer);
    json probes = json::array();
    for (const auto& p : s.probes) probes.push_back({{"value", p.value}, {"bytes", p.bytes}});
    search.update({{"knob", entry.size_knob->key},
                   {"value", params[entry.size_knob->key]},
                   {"bytes", s.bytes},
                   {"ratio", s.ratio},
                   {"reached", s.reached},
                   {"note", s.note},
                   {"probes", probes}});
  } else {
    search.update({{"knob", entry.size_knob ? json(entry.size_knob->key) : json(nullptr)},
                   {"reached", nullptr},
                   {"note", entry.size_knob ? "the experiment fixes the size knob"
                                            : "no size knob: its storage is what it is"}});
  }
  return {std::move(params), std::move(search)};
}

// One backend at the target storage: its parameters there, then the measurement.
EqualStoragePoint measure_at_equal_storage(const ExperimentSpec& spec, const SceneBench& bench,
                                           const std::string& scene, const std::string& backend,
                                           std::uint64_t target, StageCache& cache,
                                           const BenchOptions& bo,
                                           const std::function<void(const std::string&)>& report) {
  auto [params, search] =
      equal_storage_params(spec, bench, scene, backend, target, cache, bo, report);
  report(fmt::format("{} {}: measuring", scene, backend));
  PointOutcome out = measure_point(bench, spec, backend, params, true, cache, bo);
  const double bytes = out.record["storage_bytes"].get<double>();
  const double ratio = bytes / static_cast<double>(target);
  out.record["role"] = "equal_storage";
  out.record["target_bytes"] = target;
  out.record["storage_ratio"] = ratio;
  out.record["reached"] = std::abs(ratio - 1.0) <= spec.target.tolerance;
  if (!search.contains("bytes")) search["bytes"] = out.record["storage_bytes"];
  search["ratio"] = ratio;
  search["reached"] = out.record["reached"];
  return {std::move(out), std::move(search)};
}

// One compression on every rank together (inside a CollectiveScope, so that a backend that
// splits its work does), unless the root finds it in the stage cache: then each rank loads it
// (or, not finding it in a node-local cache, computes it alone). The root's look decides for
// all, as in `prtlab compress` on several ranks, so no rank waits in a collective the others
// skip.
CompressionResult compress_together(Communicator& comm, const std::string& backend,
                                    const std::map<std::string, std::string>& compression,
                                    const TransferInput& input, const Hash128& transfer_key,
                                    StageCache& cache, CacheMode mode, bool show_progress) {
  const Hash128 key = compression_key(backend, compression, transfer_key);
  const bool hit =
      comm.broadcast(
          {static_cast<std::uint8_t>(comm.is_root() && mode == CacheMode::kUse &&
                                     cache.contains(compression_stage(backend), key))})[0] != 0;
  if (hit) return compress_cached(backend, compression, input, transfer_key, cache, mode, false);
  std::optional<CompressionResult> out;
  std::exception_ptr failure;
  try {
    const CollectiveScope together(comm);
    out = compress_cached(backend, compression, input, transfer_key, cache, CacheMode::kRefresh,
                          show_progress);
  } catch (const ParameterError&) {
    failure = std::current_exception();  // the parameters are checked alike on every rank
  } catch (const CollectiveError&) {
    failure = std::current_exception();  // thrown on every rank together
  } catch (const std::exception& e) {
    // An error on this rank alone (memory, a file) may leave the others waiting in one of the
    // compression's collectives: end every rank rather than hang.
    std::fprintf(stderr, "prtlab: rank %d: %s: the collective compression failed: %s\n",
                 comm.rank(), backend.c_str(), e.what());
    DistributedSession::abort(1);
  }
  if (comm.any(failure != nullptr)) {
    if (failure) std::rethrow_exception(failure);
    throw CollectiveError(
        fmt::format("{}: the collective compression failed on another rank", backend));
  }
  return std::move(*out);
}

// Failures the ranks of a distributed run met, by scene and point label ("" for the scene).
using KnownFailures = std::map<std::pair<std::string, std::string>, std::string>;

json gather_failures(Communicator& comm, const json& mine) {
  const std::string text = mine.dump();
  const auto all =
      comm.gather(std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
  json merged = json::array();
  for (const auto& bytes : all)
    for (auto& f : json::parse(bytes.begin(), bytes.end())) merged.push_back(std::move(f));
  const std::string out = merged.dump();
  const auto back = comm.broadcast(std::vector<std::uint8_t>(out.begin(), out.end()));
  return json::parse(back.begin(), back.end());
}

// A distributed run's first pass: the scenes' stages, then every point, handed out to the ranks
// by work queues (a slow point holds up only its rank) and measured into the shared stage
// cache. The root's single-process pass then finds every point there and writes exactly the
// files one process writes. Returns every rank's failures, so that the root records them
// without measuring those points again.
KnownFailures warm_stage_cache(const ExperimentSpec& spec,
                               const std::vector<SceneVariant>& variants, StageCache& cache,
                               const BenchOptions& bo, const RunOptions& o, Communicator& comm) {
  const auto say = [&](const std::string& line) {
    if (o.on_progress)
      o.on_progress(fmt::format("[rank {}/{}] {}", comm.rank(), comm.size(), line));
  };
  // Every rank must file its points under the root's keys, which name the device.
  const std::string device = bo.device ? bo.device->info().label() : std::string("none");
  const auto root_device = comm.broadcast(std::vector<std::uint8_t>(device.begin(), device.end()));
  if (comm.any(std::string(root_device.begin(), root_device.end()) != device))
    throw ParameterError(fmt::format(
        "the ranks measure on different OpenCL devices (rank 0: '{}', rank {}: '{}'): the root "
        "would find none of the others' points; give every rank the same --device",
        std::string(root_device.begin(), root_device.end()), comm.rank(), device));
  json failures = json::array();
  const auto failed = [&](const std::string& scene, const std::string& what,
                          const std::string& why) {
    failures.push_back({{"scene", scene}, {"point", what}, {"error", why}});
    say(fmt::format("warning: {} {} failed: {}", scene, what.empty() ? "(scene)" : what, why));
  };
  {
    WorkQueue scenes(comm, variants.size());
    while (const auto i = scenes.next()) {
      const SceneVariant& v = variants[*i];
      say(fmt::format("{}: exact transfer, materials, exact images", v.name));
      try {
        const SceneBench bench = prepare_bench(v, spec, cache, bo);
        if (spec.kind == ExperimentKind::kEqualStorage)
          (void)storage_target(spec, bench, cache, bo, bo.show_progress);
      } catch (const std::exception& e) {
        failed(v.name, "", e.what());
      }
    }
  }
  failures = gather_failures(comm, failures);
  std::set<std::string> bad_scenes;
  for (const auto& f : failures) bad_scenes.insert(f["scene"].get<std::string>());

  struct Task {
    std::size_t variant;
    std::string backend;
    std::map<std::string, std::string> params;  // sweeps only
  };
  std::vector<Task> tasks;
  for (std::size_t i = 0; i < variants.size(); ++i) {
    if (bad_scenes.contains(variants[i].name)) continue;
    for (const auto& backend : spec.backends) {
      if (spec.kind == ExperimentKind::kEqualStorage)
        tasks.push_back({i, backend, {}});
      else
        for (auto& params : sweep_points(spec, backend)) tasks.push_back({i, backend, params});
    }
  }
  json mine = json::array();
  failures.swap(mine);  // from here, this rank's own
  // The scenes' stages were just stored (refreshed, with --recompute): the points load them.
  BenchOptions stored = bo;
  stored.cache_mode = CacheMode::kUse;
  std::optional<SceneBench> bench;
  std::size_t bench_of = variants.size();
  const auto bench_for = [&](std::size_t variant) -> const SceneBench& {
    if (bench_of != variant) {
      bench.reset();
      bench_of = variants.size();
      bench.emplace(prepare_bench(variants[variant], spec, cache, stored));
      bench_of = variant;
    }
    return *bench;
  };
  // Backends that split one compression over the ranks (CompressorEntry::collective): every rank
  // compresses their points together first, into the stage cache, so that a file's slowest point
  // (srbf_cta on the chair) uses the whole allocation; the work queue below then measures them
  // from the cache like any other point. A compression that fails here fails again there, alone,
  // which records it.
  // With --recompute (not kUse) the work queue below recomputes every compression anyway.
  for (std::size_t k = 0; bo.cache_mode == CacheMode::kUse && k < tasks.size(); ++k) {
    const Task& t = tasks[k];
    const auto& entry = CompressorRegistry::instance().get(t.backend);
    if (!entry.collective) continue;
    const SceneVariant& v = variants[t.variant];
    // The scene's stages and the storage target each rank finds or computes alone; every rank
    // goes on to the collective part only if all have them, so that none waits in a collective
    // another skipped. compress_together makes a compression's errors every rank's.
    std::optional<std::uint64_t> target;
    bool ready = true;
    try {
      const SceneBench& b = bench_for(t.variant);
      if (spec.kind == ExperimentKind::kEqualStorage)
        target = storage_target(spec, b, cache, stored, bo.show_progress);
    } catch (const std::exception&) {
      ready = false;  // the work queue below meets the same error and records it
    }
    if (comm.any(!ready)) continue;
    try {
      const SceneBench& b = bench_for(t.variant);
      const CompressFn together = [&](const std::map<std::string, std::string>& compression) {
        return compress_together(comm, t.backend, compression, b.prepared.input(entry),
                                 b.prepared.transfer.key, cache, bo.cache_mode, bo.show_progress);
      };
      std::map<std::string, std::string> params = t.params;
      if (spec.kind == ExperimentKind::kEqualStorage) {
        say(fmt::format("{} {}: compressing on every rank together", v.name, t.backend));
        params =
            equal_storage_params(
                spec, b, v.name, t.backend, *target, cache, bo, [](const std::string&) {}, together)
                .params;
      } else {
        say(fmt::format("{} {}: compressing on every rank together", v.name,
                        point_label(t.backend, t.params)));
      }
      (void)together(split_point_params(entry, params).compression);
    } catch (const std::exception& e) {
      log_debug("{} {}: the collective compression failed ({}); measured alone below", v.name,
                t.backend, e.what());
    }
  }
  {
    WorkQueue points(comm, tasks.size());
    while (const auto k = points.next()) {
      const Task& t = tasks[*k];
      const SceneVariant& v = variants[t.variant];
      const std::string what =
          spec.kind == ExperimentKind::kEqualStorage ? t.backend : point_label(t.backend, t.params);
      try {
        const SceneBench& b = bench_for(t.variant);
        if (spec.kind == ExperimentKind::kEqualStorage) {
          const std::uint64_t target = storage_target(spec, b, cache, stored, bo.show_progress);
          (void)measure_at_equal_storage(spec, b, v.name, t.backend, target, cache, bo, say);
        } else {
          say(fmt::format("{} {}", v.name, what));
          (void)measure_point(b, spec, t.backend, t.params, false, cache, bo);
        }
      } catch (const std::exception& e) {
        failed(v.name, what, e.what());
      }
    }
  }
  for (auto& f : gather_failures(comm, failures)) mine.push_back(std::move(f));
  KnownFailures known;
  for (const auto& f : mine)
    known.emplace(std::pair{f["scene"].get<std::string>(), f["point"].get<std::string>()},
                  f["error"].get<std::string>());
  return known;
}

}  // namespace

fs::path result_folder(const ExperimentSpec& spec, const fs::path& out_root) {
  return out_root / (spec.variant.empty() || spec.variant == "full"
                         ? spec.name
                         : spec.name + "-" + spec.variant);
}

RunSummary run_experiment(const ExperimentSpec& spec_in, const RunOptions& o) {
  ExperimentSpec spec = spec_in;
  if (!o.scenes.empty()) spec.scenes = o.scenes;
  // The size of the run and every input the file names are checked before any folder or
  // stage is touched.
  check_point_budget(spec, o.max_points);
  check_environments(spec);
  RunSummary summary;
  summary.folder = result_folder(spec, o.out_root);
  std::vector<std::string> previous_files;
  const fs::path& folder = summary.folder;
  // Scenes resolve before the folder is looked at: a missing scene is the error to report,
  // not "pass --force".
  StageCache cache = o.cache_root ? StageCache(*o.cache_root) : StageCache();
  std::vector<SceneVariant> variants;
  for (const auto& s : spec.scenes)
    for (auto& v : scene_variants(s, spec.scene_grid, cache.root() / "derived-scenes"))
      variants.push_back(std::move(v));
  bool was_complete = fs::exists(folder / ".complete");
  // The root's folder decides for every rank (the results may live on its filesystem only).
  if (o.comm && o.comm->distributed())
    was_complete =
        o.comm->broadcast({static_cast<std::uint8_t>(was_complete && o.comm->is_root())})[0] != 0;
  if (was_complete && !o.force)
    throw ParameterError(fmt::format(
        "{} holds a complete run; pass --force to overwrite it, or redraw its report with "
        "prtlab experiment report {}",
        folder.string(), folder.string()));
  const CacheMode mode = o.recompute ? CacheMode::kRefresh : CacheMode::kUse;
  BenchOptions bo{o.device, mode, o.show_progress_bars};
  KnownFailures known;
  if (o.comm && o.comm->distributed()) {
    known = warm_stage_cache(spec, variants, cache, bo, o, *o.comm);
    summary.ranks = o.comm->size();
    if (!o.comm->is_root()) return summary;  // the root writes the files
    bo.cache_mode = CacheMode::kUse;         // what the ranks just stored
  }
  if (was_complete) {
    // The old files stay until the new run has written its own; then those of the old
    // manifest that the new run did not write again are removed (nothing else in the folder
    // is touched). Without .complete an interrupted forced run resumes like any other.
    previous_files = manifest_of(folder / ".complete");
    fs::remove(folder / ".complete");
  }
  summary.resumed = fs::exists(folder / ".started");
  fs::create_directories(folder);
  write_text_atomically(folder / ".started",
                        "a run of this experiment started here; without "
                        ".complete beside it, it did not finish\n");

  const Provenance prov = collect_provenance(o.command_line, o.device);
  // Other processes change every timing; the report records how busy the machine was.
  std::string load;
  if (std::ifstream in("/proc/loadavg"); in) std::getline(in, load);

  const RunPlan plan = plan_run(spec, variants);
  const std::size_t planned = plan.points;
  if (o.on_progress) o.on_progress(fmt::format("{}: {}", spec.name, plan.summary()));

  const std::string tag = spec.variant.empty() ? spec.name : spec.name + " " + spec.variant;
  std::size_t done = 0, computed = 0, hits = 0;
  double computed_seconds = 0, saved_seconds = 0;
  const auto report = [&](const std::string& what) {
    if (!o.on_progress) return;
    const double eta = computed ? computed_seconds / static_cast<double>(computed) *
                                      static_cast<double>(planned - std::min(done, planned))
                                : NAN;
    o.on_progress(fmt::format("[{} {}/{}, ETA {}] {}", tag, std::min(done + 1, planned), planned,
                              computed ? duration(eta) : std::string("?"), what));
  };
  if (summary.resumed && o.on_progress)
    o.on_progress(
        fmt::format("resuming the interrupted run in {} (finished points load from "
                    "the stage cache)",
                    folder.string()));

  json points = json::array(), searches = json::array(), scenes = json::array(),
       image_sets = json::array();
  // The ETA counts the whole wall time of a computed point: its storage search, its
  // measurement and its share of the scene's preparation.
  auto since = std::chrono::steady_clock::now();
  const auto account = [&](const PointOutcome& out) {
    ++done;
    const double wall = seconds_since(since);
    since = std::chrono::steady_clock::now();
    if (out.cache_hit) {
      ++hits;
      saved_seconds += number_or_nan(out.record["measure_seconds"]);
    } else {
      ++computed;
      computed_seconds += std::max(wall, out.seconds);
    }
    if (o.stop_after_points > 0 && static_cast<int>(done) >= o.stop_after_points)
      throw RunInterrupted(fmt::format("stopped after {} points", done));
  };

  // A point or scene that fails (a backend refusing the scene, a device out of memory) is
  // recorded and reported; the others still run, and nothing of it is cached.
  json failures = json::array();
  const auto fail = [&](const std::string& scene, const std::string& what, const std::string& why) {
    failures.push_back({{"scene", scene}, {"point", what}, {"error", why}});
    // A failed point counts as done for the progress line, and its time stays out of the ETA.
    if (!what.empty()) ++done;
    since = std::chrono::steady_clock::now();
    if (o.on_progress)
      o.on_progress(
          fmt::format("warning: {} {} failed: {}", scene, what.empty() ? "(scene)" : what, why));
  };

  for (const auto& variant : variants) {
    report(fmt::format("{}: exact transfer, materials, exact images", variant.name));
    std::optional<SceneBench> prepared;
    if (const auto f = known.find({variant.name, ""}); f != known.end()) {
      fail(variant.name, "", f->second);
      continue;
    }
    try {
      prepared.emplace(prepare_bench(variant, spec, cache, bo));
    } catch (const RunInterrupted&) {
      throw;
    } catch (const std::exception& e) {
      fail(variant.name, "", e.what());
      continue;
    }
    SceneBench& bench = *prepared;
    json scene_info = bench.info;
    if (spec.kind == ExperimentKind::kEqualStorage) {
      report(fmt::format("{}: target storage", variant.name));
      const std::uint64_t target = storage_target(spec, bench, cache, bo, o.show_progress_bars);
      scene_info["target_bytes"] = target;
      scene_info["target_backend"] =
          spec.target.megabytes ? json(nullptr) : json(spec.target.backend);
      std::vector<PointOutcome> outcomes;
      outcomes.reserve(spec.backends.size());
      for (const auto& backend : spec.backends) try {
          if (const auto f = known.find({variant.name, backend}); f != known.end()) {
            fail(variant.name, backend, f->second);
            continue;
          }
          EqualStoragePoint e = measure_at_equal_storage(spec, bench, variant.name, backend, target,
                                                         cache, bo, report);
          searches.push_back(std::move(e.search));
          account(e.outcome);
          outcomes.push_back(std::move(e.outcome));
        } catch (const RunInterrupted&) {
          throw;
        } catch (const std::exception& e) {
          fail(variant.name, backend, e.what());
        }
      if (spec.images) {
        std::vector<PointOutcome*> ptrs;
        for (auto& out : outcomes) ptrs.push_back(&out);
        image_sets.push_back(
            {{"scene", variant.name}, {"images", write_scene_images(bench, ptrs, folder)}});
      }
      for (auto& out : outcomes) points.push_back(std::move(out.record));
    } else {
      for (const auto& backend : spec.backends)
        for (const auto& params : sweep_points(spec, backend)) {
          const std::string what = point_label(backend, params);
          if (const auto f = known.find({variant.name, what}); f != known.end()) {
            fail(variant.name, what, f->second);
            continue;
          }
          try {
            report(fmt::format("{} {}", variant.name, what));
            PointOutcome out = measure_point(bench, spec, backend, params, false, cache, bo);
            out.record["role"] = "sweep";
            account(out);
            points.push_back(std::move(out.record));
          } catch (const RunInterrupted&) {
            throw;
          } catch (const std::exception& e) {
            fail(variant.name, what, e.what());
          }
        }
    }
    scenes.push_back(std::move(scene_info));
  }
  mark_pareto(points);
  // After a distributed first pass every point is in the shared cache; a point the root has to
  // compute again means the ranks wrote where the root does not read (a node-local cache), and
  // the run quietly became a one-process run on the root.
  if (summary.ranks > 1 && computed > 0)
    log_warn_named("ranks-cache-not-shared",
                   "the root computed {} of {} points again that the {} ranks had measured: is "
                   "the stage cache ({}) on a filesystem every node shares? (docs/distributed.md)",
                   computed, computed + hits, summary.ranks, cache.root().string());

  const json spec_json = to_json(spec);
  json prov_json = to_json(prov);
  prov_json["summary"] = prov.summary();
  prov_json["load_average_at_start"] = load;
  json result = {{"experiment", spec_json},
                 {"provenance", prov_json},
                 {"paper", spec.paper},
                 {"paper_source", spec.paper_source},
                 {"scenes", scenes},
                 {"searches", searches},
                 {"image_sets", image_sets},
                 {"points", points},
                 {"failures", failures},
                 {"cache",
                  {{"points_from_cache", hits},
                   {"points_computed", computed},
                   {"points_recomputed_by_root", summary.ranks > 1 ? computed : 0},
                   {"seconds_saved", saved_seconds},
                   {"seconds_computing", computed_seconds},
                   {"stage_cache", cache.root().string()},
                   {"stage_hits", cache.stats().hits},
                   {"stage_misses", cache.stats().misses}}}};
  write_result_files(result, folder);
  summary.points = points.size();
  summary.failed = failures.size();
  for (const auto& f : failures) {
    if (!summary.first_failure.empty()) break;
    summary.first_failure = fmt::format(
        "{} {}: {}", f["scene"].get<std::string>(),
        f["point"].get<std::string>().empty() ? "(scene)" : f["point"].get<std::string>(),
        f["error"].get<std::string>());
  }
  // A run that measured nothing is not complete: the folder keeps .started, and the next run
  // retries every point instead of skipping a folder of failures.
  if (points.empty() && !failures.empty()) {
    summary.result = std::move(result);
    return summary;
  }
  const std::vector<std::string> files = written_files(result);
  for (const auto& f : previous_files)
    if (!std::binary_search(files.begin(), files.end(), f) && f.find("..") == std::string::npos)
      fs::remove(folder / f);
  write_text_atomically(folder / ".complete", json({{"date_utc", prov.date_utc},
                                                    {"git", prov.git_hash},
                                                    {"points", points.size()},
                                                    {"files", files}})
                                                      .dump(2) +
                                                  "\n");
  fs::remove(folder / ".started");
  summary.complete = true;
  summary.result = std::move(result);
  return summary;
}

}  // namespace prt::experiments
