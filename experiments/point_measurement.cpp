#include "point_measurement.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "prtlab/base/build_info.h"
#include "prtlab/base/error.h"
#include "prtlab/base/statistics.h"
#include "prtlab/compress/compression_stage.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/light_options.h"
#include "prtlab/lighting/environment_map.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/render/frame_renderer.h"
#include "prtlab/render/image_error.h"
#include "prtlab/storage/archive.h"

namespace prt::experiments {
namespace {

using json = nlohmann::json;

// Bump when a point's record changes meaning or layout: cached points are then recomputed.
constexpr std::uint32_t kPointVersion = 7;
constexpr const char* kPointKind = "experiment-point";

json null_if_nan(double v) {
  return std::isfinite(v) ? json(v) : json(nullptr);
}

std::string params_string(const std::map<std::string, std::string>& p) {
  std::string s;
  for (const auto& [k, v] : p) s += (s.empty() ? "" : ";") + k + "=" + v;
  return s;
}

// Everything besides the backend and its parameters that a point's numbers depend on. An
// environment file counts by its content, not its path, so a moved data directory still hits
// and an edited EXR does not.
json evaluation_settings(const ExperimentSpec& spec, const BenchOptions& o) {
  json j = evaluation_json(spec);
  for (auto& e : j["environments"])
    if (!e["file"].get<std::string>().empty())
      e["file"] = Hasher().add_file(e["file"].get<std::string>()).digest().hex();
  j["device"] = o.device ? o.device->info().label() : std::string("none");
  return j;
}

}  // namespace

const std::vector<std::string>& point_record_columns() {
  static const std::vector<std::string> columns = {"scene",
                                                   "backend",
                                                   "params",
                                                   "role",
                                                   "knob",
                                                   "knob_value",
                                                   "storage_bytes",
                                                   "storage_mb",
                                                   "target_bytes",
                                                   "storage_ratio",
                                                   "reached",
                                                   "flops_per_relight",
                                                   "computation_percent",
                                                   "compress_seconds",
                                                   "compress_cache_hit",
                                                   "relight_ms_cpp",
                                                   "relight_ms_opencl",
                                                   "opencl_vs_cpp_rel_l2",
                                                   "device",
                                                   "lstar_rel_l2_mean",
                                                   "lstar_rel_l2_max",
                                                   "frobenius_rel",
                                                   "frobenius_stderr",
                                                   "frobenius_se",
                                                   "frobenius_exact",
                                                   "frobenius_se_declared",
                                                   "max_vertex_rel",
                                                   "image_rel_l2_mean",
                                                   "image_rel_l2_max",
                                                   "image_psnr_db_mean",
                                                   "image_psnr_db_min",
                                                   "frame_ms_view",
                                                   "frame_ms_light",
                                                   "fps_view",
                                                   "fps_light",
                                                   "culls",
                                                   "visible_vertices",
                                                   "relight_ms_frame_culled",
                                                   "relight_ms_frame_unculled",
                                                   "frame_ms_light_unculled",
                                                   "cull_speedup",
                                                   "cull_identical",
                                                   "image_exact_count",
                                                   "declared_error_bound",
                                                   "lossless",
                                                   "vertices",
                                                   "local_grid",
                                                   "cubemap_resolution",
                                                   "supersampling",
                                                   "nnz",
                                                   "pareto_time",
                                                   "pareto_storage",
                                                   "point_key",
                                                   "backend_metrics"};
  return columns;
}

const std::vector<std::string>& error_record_columns() {
  static const std::vector<std::string> columns = {
      "scene",        "backend",      "params",        "environment",     "view",
      "lstar_rel_l2", "image_rel_l2", "image_psnr_db", "relight_ms_frame"};
  return columns;
}

PointOutcome measure_point(const SceneBench& b, const ExperimentSpec& spec,
                           const std::string& backend,
                           const std::map<std::string, std::string>& params, bool keep_images,
                           StageCache& cache, const BenchOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto& registry = CompressorRegistry::instance();
  const CompressorEntry& entry = registry.get(backend);
  // Light options (light_options.h) are not compressed: they join the point's parameters only
  // where they differ from their defaults, so a point that does not set them keeps its key.
  const PointParams split = split_point_params(entry, params);
  auto canonical = ParamSet(backend, entry.params, split.compression).canonical();
  for (const auto& [k, v] : canonical_light_options(entry, split.light)) canonical[k] = v;
  const bool images = spec.images && keep_images;
  Hasher h;
  h.add(kPointKind).add(kPointVersion).add(b.prepared.transfer.key).add(backend).add(entry.version);
  for (const auto& [k, v] : canonical) h.add(k).add(v);
  h.add(evaluation_settings(spec, o).dump()).add(build_info().git_hash).add(images);
  const Hash128 key = h.digest();
  const std::size_t pixels = static_cast<std::size_t>(spec.width) * spec.height;

  PointOutcome out;
  bool computed = false;
  const auto compute = [&]() {
    computed = true;
    const auto tm = std::chrono::steady_clock::now();
    const TransferMatrix& t = b.prepared.transfer.result.transfer;
    CompressionResult cr =
        compress_cached(backend, split.compression, b.prepared.input(entry),
                        b.prepared.transfer.key, cache, o.cache_mode, o.show_progress);
    const StorageReport storage = cr.compressed->storage();
    const double flops = cr.compressed->flops_per_relight();
    json r;
    for (const auto& c : point_record_columns()) r[c] = nullptr;
    r["scene"] = b.variant.name;
    r["backend"] = backend;
    r["params"] = params_string(canonical);
    if (entry.size_knob) {
      r["knob"] = entry.size_knob->key;
      r["knob_value"] = canonical.at(entry.size_knob->key);
    }
    r["storage_bytes"] = storage.total_bytes();
    r["storage_mb"] = static_cast<double>(storage.total_bytes()) / 1e6;
    r["flops_per_relight"] = flops;
    r["computation_percent"] = t.nnz() ? 100.0 * flops / (2.0 * static_cast<double>(t.nnz())) : 0.0;
    if (spec.timing) r["compress_seconds"] = cr.compress_seconds;
    r["compress_cache_hit"] = cr.cache_hit;
    r["declared_error_bound"] = cr.compressed->declared_error_bound();
    r["lossless"] = entry.lossless;
    r["vertices"] = t.vertex_count();
    r["local_grid"] = b.info.at("local_grid");
    r["cubemap_resolution"] = b.info.at("cubemap_resolution");
    r["supersampling"] = b.info.at("supersampling");
    r["nnz"] = t.nnz();
    r["point_key"] = key.hex();
    json components = json::array();
    for (const auto& c : storage.components)
      components.push_back({{"name", c.name}, {"bytes", c.bytes}});
    r["storage_components"] = components;
    r["canonical_params"] = canonical;

    EvaluationOptions eo;
    eo.repeats = spec.timing ? spec.repeats : 1;
    eo.frobenius_relights = spec.frobenius_relights;
    eo.light_options = split.light;
    const BackendEvaluation ev = evaluate_backend(*cr.compressed, t, b.lights, o.device, eo);
    r["device"] = ev.device;
    if (spec.timing) {
      r["relight_ms_cpp"] = ev.ms_cpp;
      r["relight_ms_opencl"] = ev.ms_opencl ? json(*ev.ms_opencl) : json(nullptr);
    }
    r["opencl_vs_cpp_rel_l2"] = ev.opencl_vs_cpp ? json(*ev.opencl_vs_cpp) : json(nullptr);
    r["lstar_rel_l2_mean"] = ev.mean_rel_l2;
    r["lstar_rel_l2_max"] = ev.max_rel_l2;
    if (ev.frobenius.relights > 0) {  // else skipped: frobenius_relights = 0
      r["frobenius_rel"] = ev.frobenius.relative;
      r["frobenius_stderr"] = ev.frobenius.standard_error;
      r["frobenius_exact"] = ev.frobenius.exact;
      // The squared error ||T~ - T||_F^2 the CPCA and SRBF papers report as SE.
      r["frobenius_se"] =
          ev.frobenius.relative * ev.frobenius.relative * b.info.at("frobenius_sq").get<double>();
    }
    // The backend's own ||T~ - T||_F^2 when it computes one while compressing (exact, where the
    // measured value above is an estimate from a few relights): the curves plot it.
    if (const auto expected = cr.compressed->expected_frobenius_error()) {
      r["frobenius_se_declared"] = *expected * *expected * b.info.at("frobenius_sq").get<double>();
    } else {
      r["frobenius_se_declared"] = nullptr;
    }
    r["max_vertex_rel"] = ev.max_vertex_rel;
    // What the backend measured of itself (its own signal's error, ...): null when it declares
    // nothing, so that the column stays empty for most backends.
    json metrics = json::object(), meanings = json::object();
    for (const BackendMetric& m : cr.compressed->backend_metrics()) {
      metrics[m.name] = null_if_nan(m.value);
      meanings[m.name] = m.meaning;
    }
    if (!metrics.empty()) {
      r["backend_metrics"] = metrics;
      r["backend_metric_meanings"] = meanings;
    }

    json errors = json::array();
    std::map<std::string, double> relight_by_env;  // median frame relight per environment
    ArchiveWriter w(kPointKind, kPointVersion);
    if (spec.images || spec.fps) {
      FrameRenderer renderer(b.scene.mesh, b.materials,
                             std::shared_ptr<const CompressedTransfer>(std::move(cr.compressed)),
                             o.device);
      renderer.set_light_options(split.light);
      if (spec.images) {
        std::vector<double> rel, psnr;
        for (std::size_t v = 0; v < b.cameras.size(); ++v) {
          renderer.set_camera(b.cameras[v]);
          for (std::size_t l = 0; l < b.lights.size(); ++l) {
            renderer.set_environment(b.lights[l].radiance);
            (void)renderer.render();
            const RgbImage img = renderer.image();
            const ImageError e =
                image_error(img, b.exact_images[v * b.lights.size() + l], b.masks[v]);
            rel.push_back(e.relative_l2);
            psnr.push_back(e.psnr_db);
            errors.push_back({{"environment", b.lights[l].name},
                              {"view", b.view_names[v]},
                              {"lstar_rel_l2", ev.errors[l].rel_l2},
                              {"image_rel_l2", null_if_nan(e.relative_l2)},
                              {"image_psnr_db", null_if_nan(e.psnr_db)}});
            if (images) {
              std::vector<float> px(pixels * 3);
              for (std::size_t i = 0; i < pixels; ++i)
                for (int c = 0; c < 3; ++c) px[i * 3 + c] = img.pixels[i][c];
              w.add_section(fmt::format("image{}", v * b.lights.size() + l), std::move(px));
            }
          }
        }
        // An exact image has PSNR +inf: the PSNR summary is over the others, and their count
        // says how many were exact (all exact: no PSNR at all).
        double sum = 0, mx = 0, psum = 0, pmin = INFINITY;
        int finite = 0, exact = 0;
        for (double x : rel) sum += x, mx = std::max(mx, x);
        for (double x : psnr) {
          if (std::isfinite(x)) {
            psum += x, pmin = std::min(pmin, x), ++finite;
          } else if (x > 0) {
            ++exact;
          }
        }
        r["image_rel_l2_mean"] = null_if_nan(sum / static_cast<double>(rel.size()));
        r["image_rel_l2_max"] = null_if_nan(mx);
        r["image_psnr_db_mean"] = finite ? json(psum / finite) : json(nullptr);
        r["image_psnr_db_min"] = finite ? null_if_nan(pmin) : json(nullptr);
        r["image_exact_count"] = exact;
      }
      if (spec.fps && spec.timing) {
        // View changes: the camera orbits the target; light changes: the first environment
        // rotates (cubemaps prepared beforehand), at the first view.
        std::vector<double> view_ms, light_ms;
        renderer.set_environment(b.fps_lights.front());
        for (int i = 0; i < spec.fps_frames; ++i) {
          renderer.set_camera(orbit_camera(b.cameras.front(), 360.0 * i / spec.fps_frames));
          view_ms.push_back(renderer.render().times.total_ms());
        }
        // Light changes with and without culling in alternating blocks (culled, full, culled,
        // full), so that load on the machine hits both alike. Switching culling on or off
        // changes what the device relights, so the first frame after a switch is not timed.
        std::vector<double> relight_culled, relight_unculled, light_unculled;
        renderer.set_camera(b.cameras.front());
        (void)renderer.render();
        const int block = std::max(1, spec.fps_frames / 2);
        for (int pass = 0; pass < 4; ++pass) {
          const bool cull = pass % 2 == 0;
          renderer.set_culling(cull);
          renderer.set_environment(b.fps_lights.back());
          (void)renderer.render();
          for (int i = 0; i < block; ++i) {
            const auto k = static_cast<std::size_t>((pass / 2) * block + i) % b.fps_lights.size();
            renderer.set_environment(b.fps_lights[k]);
            const FrameStats f = renderer.render();
            (cull ? light_ms : light_unculled).push_back(f.times.total_ms());
            (cull ? relight_culled : relight_unculled).push_back(f.times.relight_ms);
          }
        }
        // The image must not change: culled and unculled frames of the same light, bit for bit.
        renderer.set_culling(true);
        renderer.set_environment(b.fps_lights.front());
        const FrameStats culled = renderer.render();
        const RgbImage with_culling = renderer.image();
        renderer.set_culling(false);
        renderer.set_environment(b.fps_lights.front());
        (void)renderer.render();
        const RgbImage without = renderer.image();
        // The relight stage under each environment (culled, at the first view): a light black
        // on some cube faces relights faster where the backend skips their columns.
        renderer.set_culling(true);
        for (const auto& light : b.lights) {
          std::vector<double> ms;
          for (int i = 0; i < spec.fps_frames; ++i) {
            renderer.set_environment(light.radiance);
            ms.push_back(renderer.render().times.relight_ms);
          }
          relight_by_env[light.name] = median(ms);
        }
        r["culls"] = renderer.culls();
        r["visible_vertices"] = culled.visible_vertices;
        r["relight_ms_frame_culled"] = median(relight_culled);
        r["relight_ms_frame_unculled"] = median(relight_unculled);
        r["frame_ms_light_unculled"] = median(light_unculled);
        r["cull_speedup"] = median(relight_culled) > 0
                                ? json(median(relight_unculled) / median(relight_culled))
                                : json(nullptr);
        r["cull_identical"] = with_culling.pixels.size() == without.pixels.size() &&
                              std::memcmp(with_culling.pixels.data(), without.pixels.data(),
                                          with_culling.pixels.size() * sizeof(Rgb)) == 0;
        r["frame_ms_view"] = median(view_ms);
        r["frame_ms_light"] = median(light_ms);
        r["fps_view"] = 1000.0 / median(view_ms);
        r["fps_light"] = 1000.0 / median(light_ms);
      }
    }
    if (!spec.images)
      for (std::size_t l = 0; l < b.lights.size(); ++l)
        errors.push_back({{"environment", b.lights[l].name},
                          {"view", nullptr},
                          {"lstar_rel_l2", ev.errors[l].rel_l2},
                          {"image_rel_l2", nullptr},
                          {"image_psnr_db", nullptr}});
    for (auto& e : errors) {
      const auto it = relight_by_env.find(e.at("environment").get<std::string>());
      e["relight_ms_frame"] = it == relight_by_env.end() ? json(nullptr) : json(it->second);
    }
    r["errors"] = errors;
    r["measure_seconds"] = seconds_since(tm);
    w.add_meta("record", r);
    w.add_meta("image_count", images ? b.cameras.size() * b.lights.size() : 0);
    return w;
  };
  const auto consume = [&](const ArchiveReader& reader) {
    out.record = reader.meta().at("record");
    const auto count = reader.meta().at("image_count").get<std::size_t>();
    out.images.clear();
    for (std::size_t i = 0; i < count; ++i) {
      const auto px = reader.section<float>(fmt::format("image{}", i), pixels * 3);
      RgbImage img(spec.width, spec.height);
      for (std::size_t p = 0; p < pixels; ++p)
        img.pixels[p] = Rgb{px[p * 3], px[p * 3 + 1], px[p * 3 + 2]};
      out.images.push_back(std::move(img));
    }
  };
  cache.fetch("experiment-point", key, compute, consume, o.cache_mode);
  out.cache_hit = !computed;
  out.seconds = seconds_since(t0);
  return out;
}

}  // namespace prt::experiments
