// prtlab render / prtlab fps: bi-scale images and frame rates (docs/cli.md, docs/rendering.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"
#include "paper_numbers.h"
#include "provenance.h"
#include "prtlab/base/error.h"
#include "prtlab/base/named_warning.h"
#include "prtlab/base/statistics.h"
#include "prtlab/compress/backend_input.h"
#include "prtlab/compress/compression_stage.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/lighting/environment_map.h"
#include "prtlab/render/frame_cost_model.h"
#include "prtlab/render/frame_renderer.h"
#include "prtlab/storage/atomic_file.h"
#include "prtlab/storage/data_paths.h"
#include "prtlab/transfer/local_radiance.h"
#include "prtlab/transfer/scene_transfer.h"

namespace prt::cli {
namespace {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// Options shared by render and fps.
struct SceneCli {
  std::string scene;
  std::string backend;
  std::vector<std::string> params;
  std::vector<std::string> device_params;
  std::vector<std::string> light_params;
  std::string material = "full";
  std::vector<std::string> material_params;
  std::string env;
  double rotate_deg = 0;
  std::string view;
  std::string eye, target, up, fov, size;
  int width = 0, height = 0;  // 0: not given
  std::string filter = "nearest";
  int btf_resolution = 32;
  bool no_background = false;
  bool no_view_cache = false;
  bool json = false;
};

struct RenderCli : SceneCli {
  int background_resolution = 256;
  std::string out;
  std::string png;
  double exposure = 0;
};

struct FpsCli : SceneCli {
  int frames = 30;
  std::string out;
  bool no_cull = false;
  std::string primary_rays = "raster";
};

PrimaryRays parse_primary_rays(const std::string& name) {
  if (name == "raster") return PrimaryRays::kRaster;
  if (name == "packets") return PrimaryRays::kPackets;
  if (name == "single") return PrimaryRays::kSingle;
  throw ParameterError(fmt::format(
      "--primary-rays '{}': use raster (the default), packets or single (docs/rendering.md)",
      name));
}

void add_scene_options(CLI::App* c, SceneCli& o, bool env_required) {
  c->add_option("scene", o.scene, "Scene name or .toml path")->required();
  c->add_option("--backend,-b", o.backend, "Backend name (prtlab list)")->required();
  c->add_option("--param,-p", o.params, "Backend parameter key=value (repeatable)");
  c->add_option("--device-param", o.device_params,
                "Device option of the backend key=value, e.g. opencl_kernel=lanes (repeatable; "
                "never recompresses)");
  c->add_option("--light-param", o.light_params,
                "Light option of the backend key=value, e.g. light_terms=100 for haar (repeatable; "
                "changes the relight, never recompresses)");
  c->add_option("--material", o.material,
                "Material backend the part BTFs are shaded through (prtlab list: materials)")
      ->capture_default_str();
  c->add_option("--material-param", o.material_params, "Material parameter key=value (repeatable)");
  auto* env = c->add_option("--env", o.env,
                            "Environment map: a lat-long EXR path or a name (courtyard, ...)");
  if (env_required) env->required();
  c->add_option("--rotate", o.rotate_deg,
                "Rotate the environment about +y by this many degrees (+x towards -z)");
  c->add_option("--view", o.view, "View preset of the scene (default: its first)");
  c->add_option("--eye", o.eye, "Camera position x,y,z (overrides the preset)");
  c->add_option("--target", o.target, "Camera target x,y,z");
  c->add_option("--up", o.up, "Camera up direction x,y,z");
  c->add_option("--fov", o.fov, "Vertical field of view, degrees");
  c->add_option("--size", o.size, "Image size WxH (or --width/--height)");
  c->add_option("--width", o.width, "Image width")->check(CLI::Range(1, 16384));
  c->add_option("--height", o.height, "Image height")->check(CLI::Range(1, 16384));
  c->add_option("--filter", o.filter, "BTF texel filter")
      ->check(CLI::IsMember({"nearest", "bilinear"}));
  c->add_option("--btf-resolution", o.btf_resolution, "BTF texels per side (generated, cached)")
      ->check(CLI::Range(1, 1024));
  c->add_flag("--no-background", o.no_background, "Black background instead of the environment");
  c->add_flag("--no-view-cache", o.no_view_cache,
              "Shade in one kernel pass instead of caching b(u, e) per pixel on a view change");
  c->add_flag("--json", o.json, "Machine-readable output (docs/cli.md)");
}

// Everything a frame loop needs, built after every input was checked.
struct Prepared {
  SceneDesc desc;
  Scene scene;
  fs::path env_file;
  LatLongImage env;
  Camera camera;
  std::map<std::string, std::string> params;           // canonical
  std::map<std::string, std::string> device_options;   // as given (--device-param)
  std::map<std::string, std::string> light_options;    // as given (--light-param)
  std::map<std::string, std::string> material_params;  // canonical
  std::shared_ptr<const CompressedTransfer> compressed;
  bool transfer_cache_hit = false, compress_cache_hit = false;
  ShadingMaterials materials;
  int btf_cache_hits = 0;
  double setup_seconds = 0;
  std::optional<ClContext> ctx;
  ShadingOptions shading;
};

Prepared prepare(const SceneCli& o, int default_width, int default_height,
                 const std::string& default_env) {
  const auto t0 = Clock::now();
  Prepared p;
  // Cheap checks first, so a typo fails before any expensive stage.
  const auto assignments = ParamSet::parse_assignments(o.params);
  const auto& entry = CompressorRegistry::instance().get(o.backend);
  (void)ParamSet(o.backend, entry.params, assignments);
  p.device_options = ParamSet::parse_assignments(o.device_params, "--device-param");
  (void)CompressorRegistry::instance().device_options(o.backend, p.device_options);
  p.light_options = ParamSet::parse_assignments(o.light_params, "--light-param");
  (void)CompressorRegistry::instance().light_options(o.backend, p.light_options);
  const auto material_assignments =
      ParamSet::parse_assignments(o.material_params, "--material-param");
  const auto& material_entry = MaterialRegistry::instance().get(o.material);
  p.material_params = ParamSet(o.material, material_entry.params, material_assignments).canonical();
  p.desc = parse_scene(resolve_scene(o.scene));
  (void)scene_view(p.desc, o.view);
  const std::string env_name = o.env.empty() ? default_env : o.env;
  p.env_file = resolve_envmap(env_name);
  CameraOverrides overrides = parse_camera_overrides(o.eye, o.target, o.fov, o.size);
  if (!o.up.empty()) overrides.up = parse_vec3(o.up, "--up");
  if ((o.width || o.height) && !o.size.empty())
    throw ParameterError("give the image size either as --size WxH or as --width/--height");
  if (!overrides.width) overrides.width = o.width ? o.width : default_width;
  if (!overrides.height) overrides.height = o.height ? o.height : default_height;
  if (!std::isfinite(o.rotate_deg))
    throw ParameterError(fmt::format("--rotate must be a finite angle in degrees"));
  p.shading.filter = o.filter == "bilinear" ? TexelFilter::kBilinear : TexelFilter::kNearest;
  p.shading.background = !o.no_background;
  p.shading.cache_view_vectors = !o.no_view_cache;
  p.env = load_latlong_exr(p.env_file);

  StageCache cache;
  const bool progress = !global_options().quiet;
  PrepareOptions popt;
  popt.show_progress = progress;
  const PreparedScene scene = prepare_scene(p.desc, entry.inputs, cache, popt);
  const TransferMatrix& t = scene.transfer.result.transfer;
  p.transfer_cache_hit = scene.transfer.cache_hit;
  CompressionResult cr = compress_cached(o.backend, assignments, scene.input(entry),
                                         scene.transfer.key, cache, CacheMode::kUse, progress);
  p.params = cr.params;
  p.compress_cache_hit = cr.cache_hit;
  p.compressed = std::move(cr.compressed);

  p.scene = build_scene(p.desc);
  if (p.scene.mesh.positions.size() != t.vertex_count())
    throw Error(
        fmt::format("scene '{}': the built mesh has {} vertices but its cached transfer "
                    "has {} (stale stage cache? rerun prtlab precompute --force)",
                    p.desc.name, p.scene.mesh.positions.size(), t.vertex_count()));
  p.camera = scene_camera(p.scene, o.view, overrides);
  BtfParams bp;
  bp.resolution = o.btf_resolution;
  p.materials = load_scene_materials(p.desc, bp, cache, o.material, material_assignments, progress,
                                     &p.btf_cache_hits);
  p.ctx = open_device_from_options();
  p.setup_seconds = seconds_since(t0);
  return p;
}

Cubemap environment_cubemap(const Prepared& p, double degrees) {
  return resample_to_cubemap(degrees == 0.0 ? p.env : rotate_latlong_y(p.env, degrees),
                             p.desc.cubemap_resolution);
}

std::string device_label(const Prepared& p) {
  return p.ctx ? p.ctx->info().label() : std::string("C++ reference (no OpenCL)");
}

// What the frame loop holds and computes besides the image: the transfer's storage and FLOPs
// per relight, the parts' materials (each distinct one once) and their FLOPs per shaded pixel.
struct FrameCosts {
  std::uint64_t transfer_bytes = 0;
  double transfer_flops = 0;
  std::uint64_t material_bytes = 0;
  double material_flops_per_pixel = 0;  ///< the largest over the parts
};

FrameCosts frame_costs(const Prepared& p) {
  FrameCosts c;
  c.transfer_bytes = p.compressed->storage().total_bytes();
  c.transfer_flops = p.compressed->flops_per_relight();
  std::vector<const CompressedMaterial*> seen;
  for (const auto& m : p.materials.part_material) {
    if (std::find(seen.begin(), seen.end(), m.get()) != seen.end()) continue;
    seen.push_back(m.get());
    c.material_bytes += m->storage().total_bytes();
    c.material_flops_per_pixel = std::max(c.material_flops_per_pixel, m->flops_per_pixel());
  }
  return c;
}

nlohmann::json costs_json(const FrameCosts& c) {
  return {{"transfer_bytes", c.transfer_bytes},
          {"transfer_flops_per_relight", c.transfer_flops},
          {"material_bytes", c.material_bytes},
          {"material_flops_per_pixel", c.material_flops_per_pixel}};
}

std::string costs_text(const FrameCosts& c) {
  return fmt::format(
      "transfer {:.2f} MB, {:.2f} MFLOPs a relight; materials {:.2f} MB, {:.0f} FLOPs a shaded "
      "pixel (per channel)",
      c.transfer_bytes / 1e6, c.transfer_flops / 1e6, c.material_bytes / 1e6,
      c.material_flops_per_pixel);
}

nlohmann::json stage_json(const FrameStageTimes& t) {
  return {{"gbuffer_ms", t.gbuffer_ms},
          {"gbuffer_upload_ms", t.gbuffer_upload_ms},
          {"cull_ms", t.cull_ms},
          {"project_ms", t.project_ms},
          {"relight_ms", t.relight_ms},
          {"upload_ms", t.upload_ms},
          {"shade_ms", t.shade_ms},
          {"shade_kernel_ms", t.shade_kernel_ms},
          {"view_cache_kernel_ms", t.view_cache_kernel_ms},
          {"relight_kernel_ms", t.relight_kernel_ms},
          {"total_ms", t.total_ms()}};
}

// ---- render ----------------------------------------------------------------------------------

void run_render(const RenderCli& o) {
  const fs::path out(o.out);
  const auto ext = out.extension().string();
  if (ext != ".exr" && ext != ".png")
    throw ParameterError(fmt::format("--out '{}': the image must end in .exr or .png", o.out));
  if (!o.png.empty() && fs::path(o.png).extension() != ".png")
    throw ParameterError(fmt::format("--png '{}': must end in .png", o.png));
  if (!o.png.empty() && ext == ".png")
    throw ParameterError("--png is for the PNG beside an EXR; with --out FILE.png leave it out");
  Prepared p = prepare(o, 640, 480, "");
  const Cubemap env = environment_cubemap(p, o.rotate_deg);
  // The lighting cubemap is coarse (R = 32 for the paper scenes); the background would show
  // its pixels as blocks, so misses look up a finer resampling of the same environment.
  const Cubemap background = resample_to_cubemap(
      o.rotate_deg == 0.0 ? p.env : rotate_latlong_y(p.env, o.rotate_deg), o.background_resolution);
  FrameRenderer renderer(p.scene.mesh, p.materials, p.compressed, p.ctx ? &*p.ctx : nullptr,
                         p.shading, p.device_options);
  renderer.set_light_options(p.light_options);
  renderer.set_camera(p.camera);
  renderer.set_environment(env, &background);
  const FrameStats stats = renderer.render();
  const RgbImage image = renderer.image();

  ToneMap tm;
  tm.exposure = o.exposure;
  // --out FILE.png writes only that PNG; --out FILE.exr writes the EXR and a PNG (--png, or
  // beside the EXR).
  const fs::path png = ext == ".png"   ? out
                       : o.png.empty() ? fs::path(out).replace_extension(".png")
                                       : fs::path(o.png);
  if (out.has_parent_path()) fs::create_directories(out.parent_path());
  if (png.has_parent_path()) fs::create_directories(png.parent_path());
  if (const std::size_t bad = count_nonfinite(image.pixels))
    throw NumericalError(
        fmt::format("the rendered image has {} non-finite pixels of {} (the "
                    "light or the compressed data overflows float); nothing "
                    "written",
                    bad, image.pixels.size()));
  // The EXR and its PNG together or neither: a failing PNG path must not leave a lone EXR.
  std::string exr_written;
  std::vector<PendingFile> files;
  if (ext == ".exr") {
    files.push_back({out, [&](const fs::path& tmp) { write_exr(image, tmp); }});
    exr_written = out.string();
  }
  files.push_back({png, [&](const fs::path& tmp) { write_png(image, tmp, tm); }});
  write_files_atomically(files);

  const std::size_t hits = renderer.gbuffer().hit_count();
  if (o.json) {
    nlohmann::json j;
    j["scene"] = p.desc.name;
    j["backend"] = o.backend;
    j["parameters"] = p.params;
    j["material"] = o.material;
    j["material_parameters"] = p.material_params;
    j["env"] = p.env_file.string();
    j["rotate_deg"] = o.rotate_deg;
    j["view"] = scene_view(p.desc, o.view).name;
    j["camera"] = {{"eye", {p.camera.eye.x, p.camera.eye.y, p.camera.eye.z}},
                   {"target", {p.camera.target.x, p.camera.target.y, p.camera.target.z}},
                   {"up", {p.camera.up.x, p.camera.up.y, p.camera.up.z}},
                   {"fov_y_deg", p.camera.fov_y_deg}};
    j["width"] = image.width;
    j["height"] = image.height;
    j["hit_pixels"] = hits;
    j["filter"] = o.filter;
    j["btf_resolution"] = o.btf_resolution;
    j["view_cache"] = !o.no_view_cache;
    j["exr"] = exr_written.empty() ? nlohmann::json(nullptr) : nlohmann::json(exr_written);
    j["png"] = png.string();
    j["stages"] = stage_json(stats.times);
    j["costs"] = costs_json(frame_costs(p));
    j["setup_seconds"] = p.setup_seconds;
    j["transfer_cache_hit"] = p.transfer_cache_hit;
    j["compress_cache_hit"] = p.compress_cache_hit;
    j["device"] = p.ctx ? nlohmann::json(p.ctx->info()) : nlohmann::json(nullptr);
    print_json(std::move(j));
    return;
  }
  const auto& t = stats.times;
  std::printf("scene        %s, backend %s, material %s, env %s%s, view %s\n", p.desc.name.c_str(),
              o.backend.c_str(), o.material.c_str(), p.env_file.stem().string().c_str(),
              o.rotate_deg != 0 ? fmt::format(" rotated {} deg", o.rotate_deg).c_str() : "",
              scene_view(p.desc, o.view).name.c_str());
  std::printf("image        %d x %d, %zu hit pixels (%.1f %%), %s texels\n", image.width,
              image.height, hits, 100.0 * hits / std::max<std::size_t>(1, image.pixels.size()),
              o.filter.c_str());
  std::printf("device       %s\n", device_label(p).c_str());
  std::printf("costs        %s\n", costs_text(frame_costs(p)).c_str());
  std::printf("setup        %.2f s (transfer %s, compression %s, %d of %zu BTFs from cache)\n",
              p.setup_seconds, p.transfer_cache_hit ? "cached" : "computed",
              p.compress_cache_hit ? "cached" : "computed", p.btf_cache_hits,
              p.materials.part_material.size());
  std::printf(
      "stages (ms)  G-buffer %.2f + upload %.2f | project %.2f, relight %.2f, "
      "L* upload %.2f | shade %.2f (kernels %.2f)\n",
      t.gbuffer_ms, t.gbuffer_upload_ms, t.project_ms, t.relight_ms, t.upload_ms, t.shade_ms,
      t.shade_kernel_ms);
  if (!exr_written.empty()) std::printf("wrote        %s\n", exr_written.c_str());
  std::printf("wrote        %s\n", png.string().c_str());
}

// ---- fps -------------------------------------------------------------------------------------

// Per-stage medians over frames (each stage separately; they need not sum to the median frame).
FrameStageTimes stage_medians(const std::vector<FrameStageTimes>& frames) {
  auto med = [&](double FrameStageTimes::*field) {
    std::vector<double> v;
    for (const auto& f : frames) v.push_back(f.*field);
    return median(v);
  };
  FrameStageTimes m;
  m.gbuffer_ms = med(&FrameStageTimes::gbuffer_ms);
  m.gbuffer_upload_ms = med(&FrameStageTimes::gbuffer_upload_ms);
  m.cull_ms = med(&FrameStageTimes::cull_ms);
  m.project_ms = med(&FrameStageTimes::project_ms);
  m.relight_ms = med(&FrameStageTimes::relight_ms);
  m.upload_ms = med(&FrameStageTimes::upload_ms);
  m.shade_ms = med(&FrameStageTimes::shade_ms);
  m.shade_kernel_ms = med(&FrameStageTimes::shade_kernel_ms);
  m.view_cache_kernel_ms = med(&FrameStageTimes::view_cache_kernel_ms);
  m.relight_kernel_ms = med(&FrameStageTimes::relight_kernel_ms);
  return m;
}

struct LoopResult {
  FrameStageTimes stages;  // per-stage medians
  double median_frame_ms = 0;
  double fps = 0;
  std::uint64_t relights = 0, traces = 0;  // during the loop
  std::uint64_t relit_vertices = 0;        // during the loop
};

LoopResult summarise(const std::vector<FrameStageTimes>& frames, const FrameCounters& before,
                     const FrameCounters& after) {
  LoopResult r;
  std::vector<double> totals;
  for (const auto& f : frames) totals.push_back(f.total_ms());
  r.relit_vertices = after.relit_vertices - before.relit_vertices;
  r.median_frame_ms = median(totals);
  r.fps = r.median_frame_ms > 0 ? 1000.0 / r.median_frame_ms : 0.0;
  r.stages = stage_medians(frames);
  r.relights = after.relights - before.relights;
  r.traces = after.gbuffer_traces - before.gbuffer_traces;
  return r;
}

// The paper's "view / light" fps for the scene (experiments/paper_numbers.h): Table I for its
// four scenes, else Table II (the bunny sizes), when a table lists the scene.
struct PaperFps {
  double view = 0, light = 0;
  std::string table;
};
std::optional<PaperFps> paper_fps(const std::string& scene) {
  for (const auto& [table, name] : {std::pair{experiments::PaperTable::kTable1, "Table I"},
                                    std::pair{experiments::PaperTable::kTable2, "Table II"}}) {
    const auto row = experiments::paper_row(table, scene);
    if (!row || row->fps.empty()) continue;
    const auto slash = row->fps.find('/');
    if (slash == std::string::npos) continue;
    return PaperFps{std::stod(row->fps.substr(0, slash)), std::stod(row->fps.substr(slash + 1)),
                    name};
  }
  return std::nullopt;
}

std::string fmt_ms(double v) {
  return fmt::format("{:.2f}", v);
}

// Whether the frames ran the cached shading kernels (DeviceBtfShader::uses_view_cache).
bool view_cache_used(const FrameRenderer& r) {
  return r.device_shader() && r.device_shader()->uses_view_cache();
}

// How many light-change frames a view-change frame costs (0 when a light frame took no time).
double view_to_light_ratio(const LoopResult& view, const LoopResult& light) {
  return light.median_frame_ms > 0 ? view.median_frame_ms / light.median_frame_ms : 0.0;
}

// /proc/loadavg's three averages, read when the timed loops start ("" where unavailable):
// other processes on the machine change frame times, so the reports record it.
std::string load_average() {
  std::ifstream in("/proc/loadavg");
  double a = 0, b = 0, c = 0;
  if (!(in >> a >> b >> c)) return "";
  return fmt::format("{:.2f} / {:.2f} / {:.2f}", a, b, c);
}

std::string fps_markdown(const FpsCli& o, const Prepared& p, const FrameRenderer& r,
                         const LoopResult& view, const LoopResult& light,
                         const FrameStageCosts& stage_costs, const experiments::Provenance& prov,
                         const std::string& load) {
  const auto paper = paper_fps(p.desc.name);
  const std::size_t hits = r.gbuffer().hit_count();
  std::string md;
  md += fmt::format("# Frame rates: {}, backend `{}`, {}\n\n", p.desc.name, o.backend,
                    p.ctx ? p.ctx->info().device_name : std::string("C++ reference"));
  md += "Written by `prtlab fps` (cli/render_commands.cpp; docs/rendering.md \"Frame loop\").\n\n";
  md += "| | |\n|---|---|\n";
  md += fmt::format("| command | `{}` |\n", prov.command_line);
  md += fmt::format("| provenance | {} |\n", prov.summary());
  md += fmt::format("| device | {} |\n", device_label(p));
  md += fmt::format("| load average | {} (1 / 5 / 15 min, when the timed loops started) |\n",
                    load.empty() ? std::string("unknown") : load);
  md += fmt::format(
      "| scene | {}: {} vertices, M = {}, N = {}; BTFs {} ({} x {} texels, {} views) |\n",
      p.desc.name, p.scene.mesh.positions.size(), p.desc.local_grid * p.desc.local_grid,
      6 * p.desc.cubemap_resolution * p.desc.cubemap_resolution,
      [&] {
        std::string names;
        for (const auto& part : p.desc.parts)
          if (names.find(part.btf) == std::string::npos)
            names += (names.empty() ? "" : ", ") + part.btf;
        return names;
      }(),
      o.btf_resolution, o.btf_resolution,
      p.materials.part_material.front()->sampling().view_count());
  std::string params;
  for (const auto& [k, v] : p.params) params += (params.empty() ? "" : ", ") + k + "=" + v;
  md += fmt::format("| backend | `{}` ({}) |\n", o.backend, params);
  std::string material_params;
  for (const auto& [k, v] : p.material_params)
    material_params += (material_params.empty() ? "" : ", ") + k + "=" + v;
  md += fmt::format("| material | `{}` ({}) |\n", o.material, material_params);
  md += fmt::format("| storage and FLOPs | {} |\n", costs_text(frame_costs(p)));
  md += fmt::format(
      "| image | {} x {}, view `{}`, {} hit pixels ({:.1f} %) at the first camera, {} texels, "
      "view cache {}, G-buffer `{}` |\n",
      p.camera.width, p.camera.height, scene_view(p.desc, o.view).name, hits,
      100.0 * hits / (static_cast<double>(p.camera.width) * p.camera.height), o.filter,
      o.no_view_cache      ? "off"
      : view_cache_used(r) ? "on"
                           : "on but unused (no part's material gains from it)",
      o.primary_rays);
  md += fmt::format(
      "| frames | {} view changes (the camera orbits the target about +y, {:.1f} deg apart), {} "
      "light changes (`{}` rotated about +y, {:.1f} deg apart, cubemaps prepared before timing) "
      "|\n",
      o.frames, 360.0 / o.frames, o.frames, p.env_file.stem().string(), 360.0 / o.frames);
  md += "\n## Results\n\n";
  md +=
      "Medians over the frames. A frame is the sum of the stages it runs (wall clock, the "
      "device waited for); the image stays on the device (no read-back). Each stage's median "
      "is taken separately.\n\n";
  md += fmt::format(
      "| | view change | light change | paper, {} (2008, GTX 280) |\n|---|---:|---:|---:|\n",
      paper ? paper->table : std::string("Table I"));
  md += fmt::format(
      "| **fps** | **{:.1f}** | **{:.1f}** | {} |\n", view.fps, light.fps,
      paper ? fmt::format("{:.1f} / {:.1f}", paper->view, paper->light) : std::string("—"));
  md += fmt::format("| frame ms | {} | {} | |\n", fmt_ms(view.median_frame_ms),
                    fmt_ms(light.median_frame_ms));
  md += fmt::format("| view / light frame time | {:.2f} | | |\n", view_to_light_ratio(view, light));
  auto row = [&](const char* name, double FrameStageTimes::*f) {
    md +=
        fmt::format("| {} | {} | {} | |\n", name, fmt_ms(view.stages.*f), fmt_ms(light.stages.*f));
  };
  row("G-buffer ms", &FrameStageTimes::gbuffer_ms);
  row("G-buffer upload ms", &FrameStageTimes::gbuffer_upload_ms);
  row("light projection ms", &FrameStageTimes::project_ms);
  row("relight ms (incl. light upload, L* read-back)", &FrameStageTimes::relight_ms);
  row("relight kernels ms", &FrameStageTimes::relight_kernel_ms);
  row("L* + background upload ms", &FrameStageTimes::upload_ms);
  row("shade ms", &FrameStageTimes::shade_ms);
  row("shade kernels ms", &FrameStageTimes::shade_kernel_ms);
  row("of which view cache ms", &FrameStageTimes::view_cache_kernel_ms);
  md += fmt::format("| relights during the loop | {} | {} | |\n", view.relights, light.relights);
  md += fmt::format("| G-buffer traces during the loop | {} | {} | |\n", view.traces, light.traces);
  md += fmt::format("| vertices relit during the loop | {} | {} | |\n", view.relit_vertices,
                    light.relit_vertices);
  md += fmt::format(
      "\nSetup (not timed above): {:.1f} s (transfer {}, compression {}, {} of {} "
      "part BTFs from the stage cache).\n",
      p.setup_seconds, p.transfer_cache_hit ? "from cache" : "computed",
      p.compress_cache_hit ? "from cache" : "computed", p.btf_cache_hits,
      p.materials.part_material.size());
  md += cost_model_markdown(stage_costs);
  return md;
}

nlohmann::json loop_json(const LoopResult& r) {
  return {{"fps", r.fps},
          {"median_frame_ms", r.median_frame_ms},
          {"stages_median", stage_json(r.stages)},
          {"relights", r.relights},
          {"relit_vertices", r.relit_vertices},
          {"gbuffer_traces", r.traces}};
}

void run_fps(const FpsCli& o) {
  if (!o.out.empty() && fs::path(o.out).extension() != ".md")
    throw ParameterError(
        fmt::format("--out '{}': must end in .md (the JSON goes beside it)", o.out));
  const PrimaryRays primary_rays = parse_primary_rays(o.primary_rays);  // before any work
  Prepared p = prepare(o, 640, 480, "courtyard");
  const int n = o.frames;
  // Inputs of every frame, prepared before any timing.
  std::vector<Camera> cameras;
  std::vector<Cubemap> envs;
  for (int i = 0; i < n; ++i) {
    cameras.push_back(orbit_camera(p.camera, 360.0 * i / n));
    envs.push_back(environment_cubemap(p, o.rotate_deg + 360.0 * i / n));
  }
  FrameRenderer r(p.scene.mesh, p.materials, p.compressed, p.ctx ? &*p.ctx : nullptr, p.shading,
                  p.device_options);
  r.set_light_options(p.light_options);
  r.set_culling(!o.no_cull);
  r.set_primary_rays(primary_rays);
  // Warm-up: kernel builds, first launches, caches.
  r.set_camera(cameras[0]);
  r.set_environment(envs[0]);
  r.render();
  r.set_camera(cameras[n > 1 ? 1 : 0]);
  r.set_environment(envs[n > 1 ? 1 : 0]);
  r.render();
  r.set_camera(cameras[0]);
  r.set_environment(envs[0]);
  r.render();

  const std::string load = load_average();
  std::vector<FrameStageTimes> view_frames, light_frames;
  FrameCounters before = r.counters();
  for (int i = 1; i <= n; ++i) {
    r.set_camera(cameras[i % n]);
    view_frames.push_back(r.render().times);
  }
  const LoopResult view = summarise(view_frames, before, r.counters());
  r.set_camera(cameras[0]);
  r.render();
  before = r.counters();
  for (int i = 1; i <= n; ++i) {
    r.set_environment(envs[i % n]);
    light_frames.push_back(r.render().times);
  }
  const LoopResult light = summarise(light_frames, before, r.counters());

  const auto prov = experiments::collect_provenance(provenance().value("command", std::string()),
                                                    p.ctx ? &*p.ctx : nullptr);
  const auto paper = paper_fps(p.desc.name);
  nlohmann::json j;
  j["scene"] = p.desc.name;
  j["backend"] = o.backend;
  j["parameters"] = p.params;
  j["material"] = o.material;
  j["material_parameters"] = p.material_params;
  j["costs"] = costs_json(frame_costs(p));
  j["env"] = p.env_file.string();
  j["frames"] = n;
  j["width"] = p.camera.width;
  j["height"] = p.camera.height;
  j["view"] = scene_view(p.desc, o.view).name;
  j["filter"] = o.filter;
  j["btf_resolution"] = o.btf_resolution;
  j["view_cache"] = !o.no_view_cache;
  j["view_cache_used"] = view_cache_used(r);
  j["primary_rays"] = o.primary_rays;
  j["hit_pixels"] = r.gbuffer().hit_count();
  // Of the default view (cameras[0], where the light loop runs).
  j["culling"] = {{"enabled", r.culling()},
                  {"culls", r.culls()},
                  {"visible_vertices", r.visible_vertices().size()},
                  {"total_vertices", r.mesh().positions.size()}};
  j["view_change"] = loop_json(view);
  j["light_change"] = loop_json(light);
  j["view_to_light_frame_ratio"] = view_to_light_ratio(view, light);
  const FrameCosts costs = frame_costs(p);
  const FrameStageCosts stage_costs =
      frame_stage_costs(FrameCounts::of(r, static_cast<double>(costs.transfer_bytes),
                                        costs.transfer_flops, costs.material_flops_per_pixel,
                                        p.materials.part_material.front()->light_basis().dim),
                        view.stages, light.stages);
  j["cost_model"] = cost_model_json(stage_costs);
  j["paper"] = paper ? nlohmann::json{{"table", paper->table},
                                      {"view_fps", paper->view},
                                      {"light_fps", paper->light},
                                      {"hardware", "2008 quad Xeon + GTX 280"}}
                     : nlohmann::json(nullptr);
  j["setup_seconds"] = p.setup_seconds;
  j["load_average"] = load;
  j["device"] = p.ctx ? nlohmann::json(p.ctx->info()) : nlohmann::json(nullptr);
  j["provenance"] = experiments::to_json(prov);
  if (const auto* shader = r.device_shader()) {
    const auto b = shader->bytes_per_pass();
    j["bytes"] = {{"single_pass", b.single_pass},
                  {"view_cache", b.view_cache},
                  {"cached_shade", b.cached_shade}};
  }
  if (!o.out.empty()) {
    const fs::path md_path(o.out);
    if (md_path.has_parent_path()) fs::create_directories(md_path.parent_path());
    write_text_atomically(md_path, fps_markdown(o, p, r, view, light, stage_costs, prov, load));
    write_text_atomically(fs::path(md_path).replace_extension(".json"), j.dump(2) + "\n");
  }
  if (o.json) {
    print_json(std::move(j));
    return;
  }
  std::printf("scene        %s, backend %s, %d x %d, %d frames per loop\n", p.desc.name.c_str(),
              o.backend.c_str(), p.camera.width, p.camera.height, n);
  std::printf("device       %s\n", device_label(p).c_str());
  std::printf("culling      %s: %zu of %zu vertices visible at the default view\n",
              r.culls() ? "on" : (r.culling() ? "not supported by this backend/path" : "off"),
              r.visible_vertices().size(), r.mesh().positions.size());
  std::printf("view change  %6.1f fps  (%.2f ms: G-buffer %.2f + upload %.2f + shade %.2f)\n",
              view.fps, view.median_frame_ms, view.stages.gbuffer_ms, view.stages.gbuffer_upload_ms,
              view.stages.shade_ms);
  std::printf(
      "light change %6.1f fps  (%.2f ms: project %.2f + relight %.2f + upload %.2f + "
      "shade %.2f)\n",
      light.fps, light.median_frame_ms, light.stages.project_ms, light.stages.relight_ms,
      light.stages.upload_ms, light.stages.shade_ms);
  if (paper)
    std::printf("paper        %.1f / %.1f fps (%s, 2008 GTX 280)\n", paper->view, paper->light,
                paper->table.c_str());
  if (!o.out.empty()) std::printf("wrote        %s (+ .json)\n", o.out.c_str());
}

}  // namespace

void add_render_commands(CLI::App& app) {
  auto ro = std::make_shared<RenderCli>();
  auto* r = app.add_subcommand(
      "render", "Render a scene with BTFs under an environment (relight + G-buffer + shading)");
  add_scene_options(r, *ro, true);
  r->add_option("--out,-o", ro->out, "Output image: FILE.exr (+ a PNG beside it) or FILE.png")
      ->required();
  r->add_option("--png", ro->png, "Where to write the tone-mapped PNG (default: --out as .png)");
  r->add_option("--exposure", ro->exposure, "PNG exposure in stops (after auto exposure)");
  r->add_option("--background-res", ro->background_resolution,
                "Cubemap resolution of what misses show (the lighting uses the scene's)")
      ->check(CLI::Range(1, 2048));
  r->callback([ro] { run_render(*ro); });

  auto fo = std::make_shared<FpsCli>();
  auto* f = app.add_subcommand(
      "fps", "Median frame rates of view changes and light changes (the paper's Table I fps)");
  add_scene_options(f, *fo, false);
  f->add_option("--frames", fo->frames, "Frames per loop (median reported)")
      ->check(CLI::Range(1, 100000));
  f->add_option("--out,-o", fo->out, "Write a markdown report (and .json beside it)");
  f->add_flag("--no-cull", fo->no_cull,
              "Relight every vertex on a light change (default: only the vertices the view sees, "
              "where the backend can; the image is the same)");
  f->add_option("--primary-rays", fo->primary_rays,
                "How the G-buffer finds what each pixel sees: raster, packets (Embree packets) "
                "or single (one Embree ray a pixel, the reference)")
      ->capture_default_str();
  f->callback([fo] { run_fps(*fo); });
}

}  // namespace prt::cli
