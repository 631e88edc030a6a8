// prtlab list / prtlab compress: the compressor backends.
#include <cstdio>
#include <cstdlib>

#include "backend_description.h"
#include "commands.h"
#include "prtlab/compress/backend_evaluation.h"
#include "prtlab/compress/backend_input.h"
#include "prtlab/compress/compression_stage.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/light_options.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/distributed/communicator.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/opencl/cl_device.h"
#include "prtlab/render/frame_renderer.h"
#include "prtlab/render/image_error.h"
#include "prtlab/storage/data_paths.h"
#include "prtlab/transfer/scene_transfer.h"
#include "scene_bench.h"

namespace prt::cli {
namespace {

struct ListCli {
  bool json = false;
  std::string markdown;  ///< a backend name: print its README parameter block
};

struct CompressCli {
  std::string scene;
  std::string backend;
  std::vector<std::string> params;
  std::vector<std::string> device_params;
  std::vector<std::string> light_params;
  bool json = false;
  bool force = false;
  int lights = 8;
  int repeat = 20;
  std::string save;
  bool no_image = false;
  std::string image_environment = "courtyard";
  std::vector<int> image_size = {256, 192};
};

// A material backend in `prtlab list`: the fields transfer backends have, without the
// transfer-only ones (inputs, output basis, size knob).
nlohmann::json material_json(const MaterialEntry& e) {
  nlohmann::json params = nlohmann::json::array(), device = nlohmann::json::array();
  for (const auto& s : e.params) params.push_back(param_spec_json(s));
  for (const auto& s : e.device_params) device.push_back(param_spec_json(s));
  return {{"name", e.name},     {"description", e.description}, {"lossless", e.lossless},
          {"origin", e.origin}, {"parameters", params},         {"device_parameters", device}};
}

void print_params(const std::vector<ParamSpec>& params, const std::vector<ParamSpec>& device,
                  const std::vector<ParamSpec>& light = {}) {
  for (const auto& s : params)
    std::printf("    %-14s %-6s default %-8s %s\n", s.key.c_str(),
                std::string(to_string(s.type)).c_str(), s.default_value.c_str(), s.doc.c_str());
  for (const auto& s : device)
    std::printf("    %-14s %-6s default %-8s (device) %s\n", s.key.c_str(),
                std::string(to_string(s.type)).c_str(), s.default_value.c_str(), s.doc.c_str());
  for (const auto& s : light)
    std::printf("    %-14s %-6s default %-8s (light) %s\n", s.key.c_str(),
                std::string(to_string(s.type)).c_str(), s.default_value.c_str(), s.doc.c_str());
}

void run_list(const ListCli& o) {
  const auto& reg = CompressorRegistry::instance();
  const auto& materials = MaterialRegistry::instance();
  if (!o.markdown.empty()) {
    std::fputs(backend_markdown(reg.get(o.markdown)).c_str(), stdout);
    return;
  }
  if (o.json) {
    nlohmann::json backends = nlohmann::json::array(), material_list = nlohmann::json::array();
    for (const auto& name : reg.names()) backends.push_back(backend_json(reg.get(name)));
    for (const auto& name : materials.names())
      material_list.push_back(material_json(materials.get(name)));
    nlohmann::json shared = nlohmann::json::array();
    for (const auto& s : shared_param_specs()) shared.push_back(param_spec_json(s));
    print_json(
        {{"backends", backends}, {"materials", material_list}, {"shared_parameters", shared}});
    return;
  }
  for (const auto& name : reg.names()) {
    const auto& e = reg.get(name);
    std::printf("%s%s  %s\n", e.name.c_str(), e.lossless ? " (lossless)" : "",
                e.description.c_str());
    if (e.origin != "built-in") std::printf("    from %s\n", e.origin.c_str());
    std::printf("    output basis %s, size knob %s\n",
                std::string(to_string(e.output_basis)).c_str(), size_knob_summary(e).c_str());
    print_params(e.params, e.device_params, e.light_params);
  }
  std::printf("materials:\n");
  for (const auto& name : materials.names()) {
    const auto& e = materials.get(name);
    std::printf("%s%s  %s\n", e.name.c_str(), e.lossless ? " (lossless)" : "",
                e.description.c_str());
    if (e.origin != "built-in") std::printf("    from %s\n", e.origin.c_str());
    print_params(e.params, e.device_params);
  }
  std::printf("shared parameters:\n");
  for (const auto& s : shared_param_specs())
    std::printf("    %-14s %-6s default %-8s %s\n", s.key.c_str(),
                std::string(to_string(s.type)).c_str(), s.default_value.c_str(), s.doc.c_str());
}

}  // namespace

std::optional<ClContext> open_device_from_options() {
  const auto& g = global_options();
  if (g.no_opencl) return std::nullopt;
  return ClContext::open(DeviceRequest::resolve(g.device, g.strict_device));
}

namespace {

// Parameter values as written ("12", "0", "0.0"): equal as strings, or as numbers.
bool same_value(const std::string& a, const std::string& b) {
  if (a == b) return true;
  char* end_a = nullptr;
  char* end_b = nullptr;
  const double x = std::strtod(a.c_str(), &end_a);
  const double y = std::strtod(b.c_str(), &end_b);
  return !a.empty() && !b.empty() && *end_a == '\0' && *end_b == '\0' && x == y;
}

// The papers' numbers for this backend on this scene at these parameters.
std::vector<const PublishedNumber*> published_numbers(
    const CompressorEntry& entry, const std::string& scene,
    const std::map<std::string, std::string>& params) {
  std::vector<const PublishedNumber*> out;
  for (const auto& p : entry.published) {
    if (p.scene != scene) continue;
    bool match = true;
    for (const auto& [k, v] : p.params) {
      const auto it = params.find(k);
      match = match && it != params.end() && same_value(it->second, v);
    }
    if (match) out.push_back(&p);
  }
  return out;
}

struct ImageComparison {
  std::string environment;
  int width = 0, height = 0;
  ImageError error;
};

// The backend's image against the exact one (the `uncompressed` reference) at the scene's first
// view under one environment, through the frame loop the experiments use (scene_bench.h).
ImageComparison compare_image(const CompressCli& o, std::shared_ptr<const CompressedTransfer> ct,
                              ClContext* ctx, StageCache& cache) {
  experiments::ExperimentSpec spec;
  spec.name = "compress";
  spec.scenes = {o.scene};
  spec.backends = {o.backend};
  spec.environments = {experiments::parse_environment("--image-environment", o.image_environment)};
  spec.width = o.image_size.at(0);
  spec.height = o.image_size.at(1);
  spec.timing = false;
  spec.repeats = 1;
  const std::filesystem::path file = resolve_scene(o.scene);
  const SceneDesc desc = parse_scene(file);
  const experiments::SceneVariant variant{desc.name, desc.name, file, {}};
  const experiments::BenchOptions bo{ctx, CacheMode::kUse, !global_options().quiet};
  const experiments::SceneBench bench = experiments::prepare_bench(variant, spec, cache, bo);
  FrameRenderer renderer(bench.scene.mesh, bench.materials, std::move(ct), ctx);
  renderer.set_light_options(ParamSet::parse_assignments(o.light_params, "--light-param"));
  renderer.set_camera(bench.cameras.front());
  renderer.set_environment(bench.lights.front().radiance);
  (void)renderer.render();
  return {bench.lights.front().name, spec.width, spec.height,
          image_error(renderer.image(), bench.exact_images.front(), bench.masks.front())};
}

void run_compress(const CompressCli& o) {
  const auto params = ParamSet::parse_assignments(o.params);
  // Validate the backend and parameters before any expensive stage.
  const auto& entry = CompressorRegistry::instance().get(o.backend);
  (void)ParamSet(o.backend, entry.params, params);
  const auto device_options = ParamSet::parse_assignments(o.device_params, "--device-param");
  (void)CompressorRegistry::instance().device_options(o.backend, device_options);
  const auto light_options = ParamSet::parse_assignments(o.light_params, "--light-param");
  (void)CompressorRegistry::instance().light_options(o.backend, light_options);

  const SceneDesc desc = parse_scene(resolve_scene(o.scene));
  StageCache cache;
  PrepareOptions popt;
  popt.show_progress = !global_options().quiet;
  Communicator& world = Communicator::world();
  if (world.distributed()) {
    // On several ranks the transfer is computed by all of them (or found in the cache by the
    // root), then every rank loads it and compresses collectively: a backend that can split its
    // work (bicluster's groups) does, the others compute the same result on every rank. The
    // cache is on a shared folder (docs/distributed.md), so the root's look decides for all.
    PrecomputeOptions pre;
    pre.show_progress = popt.show_progress;
    pre.sh_order = entry.inputs.sh_order;  // the transfer prepare_scene asks for
    pre.comm = &world;
    (void)precompute_scene_transfer(desc, pre, cache);
    world.barrier();
  }
  const PreparedScene scene = prepare_scene(desc, entry.inputs, cache, popt);
  const TransferMatrix& t = scene.transfer.result.transfer;
  CacheMode mode = o.force ? CacheMode::kRefresh : CacheMode::kUse;
  std::optional<CollectiveScope> together;
  if (world.distributed()) {
    const Hash128 key = compression_key(o.backend, params, scene.transfer.key);
    const bool hit =
        world.broadcast(
            {static_cast<std::uint8_t>(world.is_root() && mode == CacheMode::kUse &&
                                       cache.contains(compression_stage(o.backend), key))})[0] != 0;
    // Only a computation is collective: on a hit each rank loads (a rank that finds the entry
    // unreadable recomputes alone, outside the scope).
    if (!hit) {
      mode = CacheMode::kRefresh;
      together.emplace(world);
    }
  }
  CompressionResult cr = compress_cached(o.backend, params, scene.input(entry), scene.transfer.key,
                                         cache, mode, !global_options().quiet);
  together.reset();
  if (!world.is_root()) return;  // the root measures and reports
  auto ctx = open_device_from_options();
  const auto lights = evaluation_lights(desc.cubemap_resolution, o.lights);
  const BackendEvaluation ev = evaluate_backend(
      *cr.compressed, t, lights, ctx ? &*ctx : nullptr,
      {.repeats = o.repeat, .device_options = device_options, .light_options = light_options});
  if (!o.save.empty()) save_compressed(*cr.compressed, o.save);

  const StorageReport storage = cr.compressed->storage();
  const double mflops = cr.compressed->flops_per_relight() / 1e6;
  const double exact_mflops = 2.0 * static_cast<double>(t.nnz()) / 1e6;
  const auto paper = published_numbers(entry, desc.name, cr.params);
  std::shared_ptr<const CompressedTransfer> compressed = std::move(cr.compressed);
  const std::optional<ImageComparison> image =
      o.no_image ? std::nullopt
                 : std::optional(compare_image(o, compressed, ctx ? &*ctx : nullptr, cache));
  if (o.json) {
    nlohmann::json j;
    j["scene"] = desc.name;
    j["backend"] = o.backend;
    j["parameters"] = cr.params;
    j["light_options"] = light_options;
    j["cache_hit"] = cr.cache_hit;
    j["compress_seconds"] = cr.compress_seconds;
    j["storage_bytes"] = storage.total_bytes();
    nlohmann::json comps = nlohmann::json::array();
    for (const auto& c : storage.components)
      comps.push_back({{"name", c.name}, {"bytes", c.bytes}, {"layout", c.layout}});
    j["storage"] = comps;
    j["mflops_per_relight"] = mflops;
    j["exact_mflops_per_relight"] = exact_mflops;
    j["computation_percent"] = 100.0 * mflops / exact_mflops;
    j["dense_bytes"] = t.dense_bytes();
    j["data_percent"] =
        100.0 * static_cast<double>(storage.total_bytes()) / static_cast<double>(t.dense_bytes());
    j["declared_error_bound"] = compressed->declared_error_bound();
    j["declared_error_norm"] = to_string(compressed->declared_error_norm());
    j["rel_l2_error_mean"] = ev.mean_rel_l2;
    j["rel_l2_error_max"] = ev.max_rel_l2;
    nlohmann::json per = nlohmann::json::array();
    for (const auto& e : ev.errors)
      per.push_back({{"light", e.light}, {"rel_l2", e.rel_l2}, {"max_rel", e.max_rel}});
    j["errors"] = per;
    j["frobenius_rel_error"] = ev.frobenius.relative;
    j["frobenius_rel_error_stderr"] = ev.frobenius.standard_error;
    j["frobenius_exact"] = ev.frobenius.exact;
    j["max_vertex_rel_error"] = ev.max_vertex_rel;
    j["worst_vertex"] = ev.worst_vertex;
    j["ms_per_relight_cpp"] = ev.ms_cpp;
    j["ms_project_light"] = ev.ms_project;
    j["ms_per_relight_opencl"] =
        ev.ms_opencl ? nlohmann::json(*ev.ms_opencl) : nlohmann::json(nullptr);
    j["opencl_vs_cpp_rel_l2"] =
        ev.opencl_vs_cpp ? nlohmann::json(*ev.opencl_vs_cpp) : nlohmann::json(nullptr);
    j["device"] = ctx ? nlohmann::json(ctx->info()) : nlohmann::json(nullptr);
    if (image) {
      j["image"] = {{"environment", image->environment},
                    {"width", image->width},
                    {"height", image->height},
                    {"error", to_json(image->error)}};
    } else {
      j["image"] = nullptr;
    }
    nlohmann::json pj = nlohmann::json::array();
    for (const auto* p : paper)
      pj.push_back({{"params", p->params}, {"text", p->text}, {"source", p->source}});
    j["paper"] = pj;
    print_json(std::move(j));
    return;
  }
  std::printf("scene            %s, backend %s%s\n", desc.name.c_str(), o.backend.c_str(),
              cr.cache_hit ? "  (compressed result from cache)" : "");
  for (const auto& [k, v] : cr.params) std::printf("  %s = %s\n", k.c_str(), v.c_str());
  for (const auto& [k, v] : light_options)
    std::printf("  %s = %s (light option)\n", k.c_str(), v.c_str());
  std::printf("compress         %.2f s\n", cr.compress_seconds);
  std::printf(
      "storage          %.2f MB (%.3f %% of the dense %.0f MB)\n", storage.total_bytes() / 1e6,
      100.0 * storage.total_bytes() / static_cast<double>(t.dense_bytes()), t.dense_bytes() / 1e6);
  for (const auto& c : storage.components)
    std::printf("    %-14s %10.2f MB  %s\n", c.name.c_str(), c.bytes / 1e6, c.layout.c_str());
  for (const auto* p : paper)
    std::printf("paper            %s (%s)\n", p->text.c_str(), p->source.c_str());
  std::printf("MFLOPs/relight   %.2f (exact %.2f: %.1f %%)\n", mflops, exact_mflops,
              100.0 * mflops / exact_mflops);
  std::printf(
      "error            rel. L2 mean %.3e, max %.3e over %zu lights (declared bound %.3g)\n",
      ev.mean_rel_l2, ev.max_rel_l2, ev.errors.size(), compressed->declared_error_bound());
  std::printf("                 Frobenius %.3e%s, worst vertex %.3e (vertex %zu)\n",
              ev.frobenius.relative,
              ev.frobenius.exact ? " (exact)"
                                 : fmt::format(" (+- {:.1e}, {} relights)",
                                               ev.frobenius.standard_error, ev.frobenius.relights)
                                       .c_str(),
              ev.max_vertex_rel, ev.worst_vertex);
  if (image)
    std::printf("image            rel. L2 %.3e, PSNR %.1f dB vs the exact image (%s, %dx%d)\n",
                image->error.relative_l2, image->error.psnr_db, image->environment.c_str(),
                image->width, image->height);
  std::printf("relight C++      %.3f ms (+ %.3f ms light projection)\n", ev.ms_cpp, ev.ms_project);
  if (ev.ms_opencl)
    std::printf("relight OpenCL   %.3f ms kernel on %s (vs C++: %.2e rel. L2)\n", *ev.ms_opencl,
                ev.device.c_str(), ev.opencl_vs_cpp.value_or(0));
  else
    std::printf("relight OpenCL   n/a (%s)\n", ctx ? "backend has no kernel" : "no OpenCL device");
  if (!o.save.empty()) std::printf("saved            %s\n", o.save.c_str());
}

}  // namespace

static void run_devices(bool json) {
  const auto devices = list_devices();
  const auto chosen = open_device_from_options();
  if (json) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& d : devices) list.push_back(d.info);
    print_json({{"devices", list},
                {"selected", chosen ? nlohmann::json(chosen->info()) : nlohmann::json(nullptr)}});
    return;
  }
  if (devices.empty())
    std::printf("no OpenCL devices (install pocl-opencl-icd, or a GPU driver's ICD)\n");
  for (const auto& d : devices) std::printf("  %s\n", d.info.label().c_str());
  std::printf("selected: %s\n",
              chosen ? chosen->info().label().c_str() : "none (C++ reference paths)");
}

void add_backend_commands(CLI::App& app) {
  auto devices_json = std::make_shared<bool>(false);
  auto* dv = app.add_subcommand(
      "devices", "List the OpenCL devices and the one --device / PRTLAB_DEVICE selects");
  dv->add_flag("--json", *devices_json, "Machine-readable output (docs/cli.md)");
  dv->callback([devices_json] { run_devices(*devices_json); });

  auto lo = std::make_shared<ListCli>();
  auto* l = app.add_subcommand(
      "list", "List the registered compressor and material backends and their parameters");
  l->add_flag("--json", lo->json, "Machine-readable output (docs/cli.md)");
  l->add_option("--markdown", lo->markdown,
                "Print the parameter block of this backend's README "
                "(scripts/gen_backend_docs.py)");
  l->callback([lo] { run_list(*lo); });

  auto co = std::make_shared<CompressCli>();
  auto* c =
      app.add_subcommand("compress", "Compress a scene's transfer with a backend and measure it");
  c->add_option("scene", co->scene, "Scene name or .toml path")->required();
  c->add_option("--backend,-b", co->backend, "Backend name (prtlab list)")->required();
  c->add_option("--param,-p", co->params, "Backend parameter key=value (repeatable)");
  c->add_option("--device-param", co->device_params,
                "Device option of the backend key=value, e.g. opencl_kernel=lanes (repeatable; "
                "never recompresses)");
  c->add_option("--light-param", co->light_params,
                "Light option of the backend key=value, e.g. light_terms=100 for haar (repeatable; "
                "changes the relight, never recompresses; prtlab list shows them as (light))");
  c->add_option("--lights", co->lights, "Number of evaluation environments (1-8)")
      ->check(CLI::Range(1, 8));
  c->add_option("--repeat", co->repeat, "Timed relights (median reported)")
      ->check(CLI::Range(1, 100000));
  c->add_option("--save", co->save, "Also write the compressed transfer to this file");
  c->add_flag("--force", co->force, "Recompress even when the stage cache has the result");
  c->add_flag("--no-image", co->no_image,
              "Skip the image comparison (the backend's frame against the exact one)");
  c->add_option("--image-environment", co->image_environment,
                "Environment of the image comparison (a Blender world or sun:RATIO)");
  c->add_option("--image-size", co->image_size, "Width and height of the image comparison")
      ->expected(2)
      ->check(CLI::Range(8, 4096));
  c->add_flag("--json", co->json, "Machine-readable output (docs/cli.md)");
  c->callback([co] { run_compress(*co); });
}

}  // namespace prt::cli
