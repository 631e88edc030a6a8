// prtlab precompute / prtlab relight: the exact transfer stage and the exact relight.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <vector>

#include "commands.h"
#include "paper_numbers.h"
#include "prtlab/base/named_warning.h"
#include "prtlab/base/statistics.h"
#include "prtlab/compress/backend_evaluation.h"
#include "prtlab/compress/backend_input.h"
#include "prtlab/compress/compression_stage.h"
#include "prtlab/compress/light_options.h"
#include "prtlab/distributed/communicator.h"
#include "prtlab/lighting/environment_map.h"
#include "prtlab/storage/archive.h"
#include "prtlab/storage/data_paths.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/transfer/scene_transfer.h"

namespace prt::cli {
namespace {

// The paper's numbers for a scene: its Table I column, else its Table II column (the one table
// of experiments/paper_numbers.h).
std::optional<experiments::PaperRow> paper_row(const std::string& scene) {
  if (auto row = experiments::paper_row(experiments::PaperTable::kTable1, scene)) return row;
  return experiments::paper_row(experiments::PaperTable::kTable2, scene);
}

struct PrecomputeCli {
  std::string scene;
  bool json = false;
  bool force = false;
  int sh_order = 0;
};

struct RelightCli {
  std::string scene;
  std::string env;
  std::string out;
  bool json = false;
  int repeat = 20;
  bool eigen = true;
  std::string backend;
  std::vector<std::string> params;
  std::vector<std::string> device_params;
  std::vector<std::string> light_params;
};

void write_local_radiance(const LocalRadiance& out, const std::string& file,
                          const std::string& scene, const std::string& env,
                          const std::string& backend) {
  ArchiveWriter w("local-radiance", 1);
  w.add_meta("scene", scene);
  w.add_meta("env", env);
  w.add_meta("backend", backend);
  w.add_meta("basis", std::string(to_string(out.basis)));
  w.add_meta("dim", out.dim);
  w.add_meta("vertices", out.vertices);
  w.add_meta("prtlab", provenance());
  std::vector<float> flat(out.values.size() * 3);
  for (std::size_t i = 0; i < out.values.size(); ++i)
    for (int c = 0; c < 3; ++c) flat[3 * i + c] = out.values[i][c];
  w.add_section("rgb", std::move(flat));
  w.write(file);
}

void run_backend_relight(const RelightCli& o, const SceneDesc& desc,
                         const std::filesystem::path& env_file, Cubemap cube) {
  const auto& entry = CompressorRegistry::instance().get(o.backend);
  const auto light_options = ParamSet::parse_assignments(o.light_params, "--light-param");
  (void)CompressorRegistry::instance().light_options(o.backend, light_options);
  StageCache cache;
  PrepareOptions popt;
  popt.show_progress = !global_options().quiet;
  const PreparedScene scene = prepare_scene(desc, entry.inputs, cache, popt);
  const TransferMatrix& t = scene.transfer.result.transfer;
  const auto cr =
      compress_cached(o.backend, ParamSet::parse_assignments(o.params), scene.input(entry),
                      scene.transfer.key, cache, CacheMode::kUse, !global_options().quiet);
  auto ctx = open_device_from_options();
  std::vector<EvaluationLight> lights;
  lights.push_back({env_file.stem().string(), std::move(cube)});
  const auto ev = evaluate_backend(
      *cr.compressed, t, lights, ctx ? &*ctx : nullptr,
      {.repeats = o.repeat,
       .device_options = ParamSet::parse_assignments(o.device_params, "--device-param"),
       .light_options = light_options});
  if (!o.out.empty()) {
    LocalRadiance out;
    cr.compressed->relight(
        project_light_with(*cr.compressed, lights.front().radiance, light_options), out);
    write_local_radiance(out, o.out, desc.name, env_file.string(), o.backend);
  }
  if (o.json) {
    nlohmann::json j;
    j["scene"] = desc.name;
    j["env"] = env_file.string();
    j["backend"] = o.backend;
    j["parameters"] = cr.params;
    j["light_options"] = light_options;
    j["repeat"] = o.repeat;
    j["ms_per_relight"] = ev.ms_cpp;
    j["ms_project_light"] = ev.ms_project;
    j["ms_per_relight_opencl"] =
        ev.ms_opencl ? nlohmann::json(*ev.ms_opencl) : nlohmann::json(nullptr);
    j["opencl_vs_cpp_rel_l2"] =
        ev.opencl_vs_cpp ? nlohmann::json(*ev.opencl_vs_cpp) : nlohmann::json(nullptr);
    j["rel_l2_error"] = ev.errors.front().rel_l2;
    j["device"] = ctx ? nlohmann::json(ctx->info()) : nlohmann::json(nullptr);
    j["output"] = o.out;
    print_json(std::move(j));
    return;
  }
  std::printf("scene          %s, env %s, backend %s\n", desc.name.c_str(),
              env_file.filename().string().c_str(), o.backend.c_str());
  std::printf("relight C++    %.3f ms (+ %.3f ms light projection), median of %d\n", ev.ms_cpp,
              ev.ms_project, o.repeat);
  if (ev.ms_opencl)
    std::printf("relight OpenCL %.3f ms kernel on %s\n", *ev.ms_opencl, ev.device.c_str());
  if (std::isnan(ev.errors.front().rel_l2))
    std::printf("error          undefined (the exact product is zero)\n");
  else
    std::printf("error          %.3e relative L2 vs the exact product\n", ev.errors.front().rel_l2);
  if (!o.out.empty()) std::printf("wrote          %s\n", o.out.c_str());
}

SceneTransfer precompute(const SceneDesc& desc, bool force, int sh_order) {
  StageCache cache;
  PrecomputeOptions opt;
  opt.sh_order = sh_order;
  opt.cache = force ? CacheMode::kRefresh : CacheMode::kUse;
  opt.show_progress = !global_options().quiet;
  opt.comm = &Communicator::world();
  return precompute_scene_transfer(desc, opt, cache);
}

void run_precompute(const PrecomputeCli& o) {
  const SceneDesc desc = parse_scene(resolve_scene(o.scene));
  const SceneTransfer st = precompute(desc, o.force, o.sh_order);
  if (!st.holds_result) return;  // a rank other than the root: the root reports
  const TransferMatrix& t = st.result.transfer;
  const std::string checksum = transfer_data_checksum(st.result);
  const TransferStats& s = st.result.stats;
  const double nnz_m = static_cast<double>(t.nnz()) / 1e6;
  const double mflops = 2.0 * static_cast<double>(t.nnz()) / 1e6;
  const double dense_mb = static_cast<double>(t.dense_bytes()) / 1e6;
  const double stored_mb = static_cast<double>(t.memory_bytes()) / 1e6;
  const std::optional<experiments::PaperRow> paper = paper_row(desc.name);
  if (o.json) {
    nlohmann::json j;
    j["scene"] = desc.name;
    j["vertices"] = t.vertex_count();
    j["local_directions"] = t.local_count();
    j["rows"] = t.rows();
    j["columns"] = t.cols();
    j["supersampling"] = t.supersampling();
    j["nnz"] = t.nnz();
    j["nnz_millions"] = nnz_m;
    j["mflops_per_relight"] = mflops;
    j["dense_mb"] = dense_mb;
    j["stored_bytes"] = t.memory_bytes();
    j["sh_order"] = st.result.sh ? st.result.sh->order() : 0;
    j["cache_hit"] = st.cache_hit;
    j["cache_file"] = st.cache_file.string();
    j["seconds_this_run"] = st.seconds;
    j["precompute_seconds"] = s.seconds_total;
    j["mesh_seconds"] = st.mesh_seconds;
    j["rays_traced"] = s.rays_traced;
    j["rays_per_second"] = s.rays_per_second();
    j["threads"] = s.threads;
    j["ranks"] = s.ranks;
    j["data_checksum"] = checksum;
    if (!st.shares.empty()) {
      nlohmann::json shares = nlohmann::json::array();
      for (const auto& r : st.shares)
        shares.push_back({{"rank", r.rank},
                          {"points", r.points},
                          {"chunks", r.chunks},
                          {"seconds_tracing", r.seconds_tracing},
                          {"bytes_sent", r.bytes_sent}});
      j["rank_shares"] = shares;
    }
    j["time_breakdown"] = {{"setup", s.seconds_setup},
                           {"points", s.seconds_points},
                           {"assemble", s.seconds_assemble},
                           {"thread_seconds_trace", s.thread_seconds_trace},
                           {"thread_seconds_bin", s.thread_seconds_bin},
                           {"thread_seconds_sh", s.thread_seconds_sh}};
    if (paper)
      j["paper"] = {{"nnz_millions", paper->nnz_millions},
                    {"mflops", paper->mflops},
                    {"dense_mb", paper->data_mb}};
    j["parameters"] = {{"local_grid", desc.local_grid},
                       {"cubemap_resolution", desc.cubemap_resolution},
                       {"supersampling", desc.supersampling}};
    print_json(std::move(j));
    return;
  }
  std::printf("scene            %s%s\n", desc.name.c_str(), st.cache_hit ? "  (cache hit)" : "");
  std::printf("vertices         %zu\n", t.vertex_count());
  std::printf("T                %zu x %zu (M = %d)\n", t.rows(), t.cols(), t.local_count());
  std::printf("nnz(T)           %.2f M%s\n", nnz_m,
              paper ? fmt::format("   (paper: {:.1f} M)", paper->nnz_millions).c_str() : "");
  std::printf("MFLOPs/relight   %.1f\n", mflops);
  std::printf("dense data       %.0f MB%s\n", dense_mb,
              paper && paper->data_mb > 0
                  ? fmt::format("   (paper: {:.0f} MB)", paper->data_mb).c_str()
                  : "");
  std::printf("stored           %.1f MB (CSR: u32 offsets, u16 columns, u8 counts)\n", stored_mb);
  std::printf("precompute       %.2f s (%s: %.2f s setup, %.2f s rays+binning, %.2f s assemble)\n",
              s.seconds_total, st.cache_hit ? "cached result" : "this run", s.seconds_setup,
              s.seconds_points, s.seconds_assemble);
  std::printf("rays             %.1f M traced, %.1f M rays/s on %d threads\n", s.rays_traced / 1e6,
              s.rays_per_second() / 1e6, s.threads);
  if (s.ranks > 1) std::printf("ranks            %d (MPI)\n", s.ranks);
  for (const auto& r : st.shares)
    std::printf("  rank %-3d       %llu vertices in %llu chunks, %.2f s, %.1f MB sent\n", r.rank,
                static_cast<unsigned long long>(r.points),
                static_cast<unsigned long long>(r.chunks), r.seconds_tracing,
                static_cast<double>(r.bytes_sent) / 1e6);
  std::printf("data checksum    %s (T and SH arrays; the archive's own also covers its timings)\n",
              checksum.c_str());
  std::printf("this run         %.2f s%s\n", st.seconds,
              st.cache_hit ? " (loaded from cache)" : "");
}

void run_relight(const RelightCli& o) {
  const SceneDesc desc = parse_scene(resolve_scene(o.scene));
  const auto env_file = resolve_envmap(o.env);
  const Cubemap cube = resample_to_cubemap(load_latlong_exr(env_file), desc.cubemap_resolution);
  if (!o.backend.empty()) return run_backend_relight(o, desc, env_file, cube);
  const SceneTransfer st = precompute(desc, false, 0);
  const TransferMatrix& t = st.result.transfer;
  const std::vector<Rgb> light = cube.light_vector();

  LocalRadiance out(RadianceBasis::kPixel, t.local_count(), t.vertex_count());
  auto time_ms = [&](auto&& fn) {
    std::vector<double> ms;
    for (int i = 0; i < std::max(1, o.repeat); ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      fn();
      ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    return median(ms);
  };
  const double ms_all = time_ms([&] { relight_exact(t, light, out.values); });
  const double ms_one = time_ms([&] { relight_exact(t, light, out.values, RelightThreads::kOne); });
  double ms_eigen = 0;
  if (o.eigen) {
    const EigenSparseTransfer eig(t);
    const auto dense = EigenSparseTransfer::to_dense(light);
    EigenSparseTransfer::Dense res;
    ms_eigen = time_ms([&] { eig.multiply(dense, res); });
  }
  relight_exact(t, light, out.values);
  if (const std::size_t bad = count_nonfinite(out.values))
    throw NumericalError(
        fmt::format("{}: the relight has {} non-finite values of {} (the "
                    "radiance overflows float accumulation)",
                    env_file.string(), bad, out.values.size()));
  // Float vs double accumulation: the runtime precision error DESIGN.md asks to report.
  const auto ref = relight_exact_double(t, light);
  double num = 0, den = 0;
  for (std::size_t i = 0; i < ref.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      const double d = out.values[i][c] - ref[i][c];
      num += d * d;
      den += ref[i][c] * ref[i][c];
    }
  const double float_error = den > 0 ? std::sqrt(num / den) : 0.0;

  if (!o.out.empty()) write_local_radiance(out, o.out, desc.name, env_file.string(), "exact");
  if (o.json) {
    nlohmann::json j;
    j["scene"] = desc.name;
    j["env"] = env_file.string();
    j["rows"] = t.rows();
    j["nnz"] = t.nnz();
    j["repeat"] = o.repeat;
    j["ms_per_relight"] = ms_all;
    j["ms_per_relight_one_thread"] = ms_one;
    if (o.eigen) j["ms_per_relight_eigen"] = ms_eigen;
    j["gnnz_per_second"] = static_cast<double>(t.nnz()) / (ms_all * 1e6);
    j["float_vs_double_rel_l2"] = float_error;
    j["output"] = o.out;
    print_json(std::move(j));
    return;
  }
  std::printf("scene          %s, env %s\n", desc.name.c_str(),
              env_file.filename().string().c_str());
  std::printf("T              %zu x %zu, nnz %.2f M\n", t.rows(), t.cols(), t.nnz() / 1e6);
  std::printf("relight        %.3f ms (all threads), %.3f ms (one thread), median of %d\n", ms_all,
              ms_one, o.repeat);
  if (o.eigen) std::printf("eigen sparse   %.3f ms  (ratio %.2fx)\n", ms_eigen, ms_eigen / ms_all);
  std::printf("float error    %.2e relative L2 vs double accumulation\n", float_error);
  if (!o.out.empty()) std::printf("wrote          %s\n", o.out.c_str());
}

}  // namespace

void add_transfer_commands(CLI::App& app) {
  auto pre = std::make_shared<PrecomputeCli>();
  auto* p = app.add_subcommand(
      "precompute", "Compute (or load from the stage cache) the exact transfer matrix T");
  p->add_option("scene", pre->scene, "Scene name or .toml path")->required();
  p->add_flag("--json", pre->json, "Machine-readable output (docs/cli.md)");
  p->add_flag("--force", pre->force, "Recompute even when the stage cache has T");
  p->add_option("--sh-order", pre->sh_order,
                "Also compute the SH transfer of this order (n = order^2; 0: none)")
      ->check(CLI::Range(0, 10));
  p->callback([pre] { run_precompute(*pre); });

  auto rel = std::make_shared<RelightCli>();
  auto* r = app.add_subcommand("relight", "Exact relight L* = T L under an environment map, timed");
  r->add_option("scene", rel->scene, "Scene name or .toml path")->required();
  r->add_option("--env", rel->env,
                "Environment map: a lat-long EXR path or a name (courtyard, ...)")
      ->required();
  r->add_option("--out", rel->out, "Write L* as a prtlab archive (kind local-radiance)");
  r->add_option("--repeat", rel->repeat, "Timed repetitions (median reported)")
      ->check(CLI::Range(1, 100000));
  r->add_flag("--json", rel->json, "Machine-readable output (docs/cli.md)");
  r->add_flag("!--no-eigen", rel->eigen, "Skip the Eigen sparse baseline");
  r->add_option("--backend,-b", rel->backend,
                "Relight with this backend's compressed transfer (default: exact T)");
  r->add_option("--param,-p", rel->params, "Backend parameter key=value (repeatable)");
  r->add_option("--device-param", rel->device_params,
                "Device option of the backend key=value, e.g. opencl_kernel=lanes (repeatable; "
                "never recompresses)");
  r->add_option("--light-param", rel->light_params,
                "Light option of the backend key=value, e.g. light_terms=100 for haar (repeatable; "
                "changes the relight, never recompresses)");
  r->callback([rel] { run_relight(*rel); });
}

}  // namespace prt::cli
