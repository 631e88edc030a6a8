// `prtlab image diff` and `prtlab image reference`: error metrics and false-colour error images
// between two EXRs, and the brute-force path-traced reference of the bi-scale model
// (docs/image-error.md, docs/cli.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.h"
#include "provenance.h"
#include "prtlab/base/error.h"
#include "prtlab/btf/scene_btfs.h"
#include "prtlab/geometry/scene.h"
#include "prtlab/image/image_io.h"
#include "prtlab/lighting/environment_map.h"
#include "prtlab/render/biscale_reference.h"
#include "prtlab/render/frame_renderer.h"
#include "prtlab/render/image_error.h"
#include "prtlab/storage/atomic_file.h"
#include "prtlab/storage/data_paths.h"

namespace prt::cli {
namespace {
namespace fs = std::filesystem;

std::string format_metric(double v, const char* fmt_spec) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return fmt::format(fmt::runtime(fmt_spec), v);
}

void require_extension(const std::string& path, const char* ext, const char* option) {
  if (fs::path(path).extension() != ext)
    throw ParameterError(fmt::format("{} '{}': must end in {}", option, path, ext));
}

/// The report's provenance block (experiments/provenance.h): build, machine, time, command.
nlohmann::json report_provenance() {
  return experiments::to_json(
      experiments::collect_provenance(provenance()["command"].get<std::string>(), nullptr));
}

// ---- diff -----------------------------------------------------------------------------------

struct DiffOptions {
  std::string image, reference, out, mask, report;
  double scale = 0;
  bool json = false;
};

void run_diff(const DiffOptions& o) {
  if (!o.out.empty()) require_extension(o.out, ".png", "--out");
  if (!o.report.empty()) require_extension(o.report, ".json", "--report");
  if (!(o.scale >= 0) || !std::isfinite(o.scale))
    throw ParameterError(fmt::format("--scale {}: must be a finite number >= 0", o.scale));
  const RgbImage image = read_exr(o.image);
  const RgbImage reference = read_exr(o.reference);
  if (image.width != reference.width || image.height != reference.height) {
    throw ParameterError(fmt::format("{} is {} x {} but the reference {} is {} x {}", o.image,
                                     image.width, image.height, o.reference, reference.width,
                                     reference.height));
  }
  std::vector<std::uint8_t> mask;
  if (!o.mask.empty()) {
    const RgbImage m = read_exr(o.mask);
    if (m.width != image.width || m.height != image.height) {
      throw InputError(o.mask, fmt::format("the mask is {} x {} but the images are {} x {}",
                                           m.width, m.height, image.width, image.height));
    }
    mask.resize(m.pixels.size());
    for (std::size_t i = 0; i < mask.size(); ++i)
      mask[i] = std::max({m.pixels[i].x, m.pixels[i].y, m.pixels[i].z}) > 0.5f ? 1 : 0;
  }
  const ImageError e = image_error(image, reference, mask);

  nlohmann::json fc = nullptr;
  if (!o.out.empty()) {
    const FalseColour colour = error_false_colour(image, reference, mask, o.scale);
    if (fs::path(o.out).has_parent_path()) fs::create_directories(fs::path(o.out).parent_path());
    write_false_colour_png(colour, o.out);
    fc = {{"png", o.out},
          {"scale", colour.scale},
          {"eps", colour.eps},
          {"colour_map", "viridis"},
          {"quantity", "|a - b| / (|b| + eps), RGB Euclidean norms"}};
  }
  nlohmann::json j = {{"image", o.image},
                      {"reference", o.reference},
                      {"mask", o.mask.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.mask)},
                      {"width", image.width},
                      {"height", image.height},
                      {"error", to_json(e)},
                      {"false_colour", fc}};
  if (!o.report.empty()) {
    nlohmann::json report = j;
    report["provenance"] = report_provenance();
    if (fs::path(o.report).has_parent_path())
      fs::create_directories(fs::path(o.report).parent_path());
    write_text_atomically(o.report, report.dump(2) + "\n");
  }
  if (o.json) {
    print_json(std::move(j));
    return;
  }
  std::printf("image          %s (%d x %d)\n", o.image.c_str(), image.width, image.height);
  std::printf("reference      %s\n", o.reference.c_str());
  std::printf("pixels         %zu%s\n", e.pixels,
              o.mask.empty() ? "" : fmt::format(" (mask {})", o.mask).c_str());
  std::printf("relative L2    %s\n", e.non_finite == 0 && e.peak <= 0 && std::isnan(e.relative_l2)
                                         ? "undefined (the reference is zero)"
                                         : format_metric(e.relative_l2, "{:.6g}").c_str());
  std::printf("RMSE           %s\n", format_metric(e.rmse, "{:.6g}").c_str());
  std::printf("PSNR           %s dB (peak %s, the reference's largest value)\n",
              format_metric(e.psnr_db, "{:.2f}").c_str(), format_metric(e.peak, "{:.6g}").c_str());
  std::printf("max |a - b|    %s\n", format_metric(e.max_abs, "{:.6g}").c_str());
  if (e.non_finite) std::printf("non-finite     %zu pixels (metrics are NaN)\n", e.non_finite);
  if (!o.out.empty())
    std::printf("wrote          %s (relative error, viridis, 0 .. %.4g)\n", o.out.c_str(),
                fc["scale"].get<double>());
  if (!o.report.empty()) std::printf("wrote          %s\n", o.report.c_str());
}

// ---- reference ------------------------------------------------------------------------------

struct ReferenceOptions {
  std::string scene, env, view, eye, target, up, fov, size;
  double rotate_deg = 0;
  int samples = 32;
  std::uint64_t seed = 1;
  std::string filter = "nearest";
  int btf_resolution = 32;
  std::string env_lookup = "latlong";
  bool no_background = false;
  std::string out, png, stderr_out, hits_out, pointwise_out;
  double exposure = 0;
  bool json = false;
};

void run_reference(const ReferenceOptions& o) {
  require_extension(o.out, ".exr", "--out");
  if (!o.png.empty()) require_extension(o.png, ".png", "--png");
  if (!o.stderr_out.empty()) require_extension(o.stderr_out, ".exr", "--stderr");
  if (!o.hits_out.empty()) require_extension(o.hits_out, ".exr", "--hits");
  if (!o.pointwise_out.empty()) require_extension(o.pointwise_out, ".exr", "--pointwise");
  if (o.samples < 2 || o.samples > 256 || o.samples % 2 != 0)
    throw ParameterError(fmt::format("--samples {}: must be even and in [2, 256]", o.samples));
  if (!std::isfinite(o.rotate_deg)) throw ParameterError("--rotate must be a finite angle");
  const auto t0 = std::chrono::steady_clock::now();
  const SceneDesc desc = parse_scene(resolve_scene(o.scene));
  (void)scene_view(desc, o.view);
  const fs::path env_file = resolve_envmap(o.env);
  CameraOverrides overrides = parse_camera_overrides(o.eye, o.target, o.fov, o.size);
  if (!o.up.empty()) overrides.up = parse_vec3(o.up, "--up");
  LatLongImage env = load_latlong_exr(env_file);
  if (o.rotate_deg != 0) env = rotate_latlong_y(env, o.rotate_deg);

  const Scene scene = build_scene(desc);
  const Camera camera = scene_camera(scene, o.view, overrides);
  StageCache cache;
  BtfParams bp;
  bp.resolution = o.btf_resolution;
  const auto part_btfs = scene_part_btfs(desc, bp, cache, !global_options().quiet);
  const GBuffer gbuffer = render_gbuffer(scene.mesh, camera);
  const Cubemap cubemap = resample_to_cubemap(env, desc.cubemap_resolution);
  const RadianceFunction radiance =
      o.env_lookup == "cubemap" ? cubemap_lookup(cubemap) : latlong_lookup(env);
  BiscaleReferenceOptions ro;
  ro.samples_side = o.samples;
  ro.seed = o.seed;
  ro.filter = o.filter == "bilinear" ? TexelFilter::kBilinear : TexelFilter::kNearest;
  ro.background = !o.no_background;
  const BiscaleReference ref =
      render_biscale_reference(gbuffer, scene.mesh, part_btfs, radiance, ro);

  if (fs::path(o.out).has_parent_path()) fs::create_directories(fs::path(o.out).parent_path());
  write_exr(ref.radiance, o.out);
  const fs::path png = o.png.empty() ? fs::path(o.out).replace_extension(".png") : fs::path(o.png);
  if (png.has_parent_path()) fs::create_directories(png.parent_path());
  ToneMap tm;
  tm.exposure = o.exposure;
  write_png(ref.radiance, png, tm);
  if (!o.stderr_out.empty()) write_exr(ref.standard_error, o.stderr_out);
  if (!o.pointwise_out.empty()) {
    PointwiseTransferOptions po;
    po.supersampling = desc.supersampling;
    po.filter = ro.filter;
    po.background = ro.background;
    write_exr(render_pointwise_transfer(gbuffer, scene.mesh, part_btfs, cubemap, po),
              o.pointwise_out);
  }
  const auto mask = hit_mask(gbuffer);
  if (!o.hits_out.empty()) {
    RgbImage hits(gbuffer.width, gbuffer.height);
    for (std::size_t i = 0; i < mask.size(); ++i) hits.pixels[i] = Rgb(mask[i] ? 1.f : 0.f);
    write_exr(hits, o.hits_out);
  }

  // Noise level: RMS standard error over RMS radiance, over the hit pixels.
  const RgbImage zero(gbuffer.width, gbuffer.height);
  const double rms = image_error(ref.radiance, zero, mask).rmse;
  const double noise = rms > 0 ? image_error(ref.standard_error, zero, mask).rmse / rms : 0.0;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (o.json) {
    print_json(
        {{"scene", desc.name},
         {"env", env_file.string()},
         {"env_lookup", o.env_lookup},
         {"rotate_deg", o.rotate_deg},
         {"view", scene_view(desc, o.view).name},
         {"width", gbuffer.width},
         {"height", gbuffer.height},
         {"hit_pixels", gbuffer.hit_count()},
         {"samples_per_pixel", ref.samples_per_pixel},
         {"seed", o.seed},
         {"filter", o.filter},
         {"btf_resolution", o.btf_resolution},
         {"rays_traced", ref.rays_traced},
         {"render_seconds", ref.seconds},
         {"seconds", seconds},
         {"relative_noise", noise},
         {"exr", o.out},
         {"png", png.string()},
         {"stderr_exr",
          o.stderr_out.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.stderr_out)},
         {"hits_exr", o.hits_out.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.hits_out)},
         {"pointwise_exr",
          o.pointwise_out.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.pointwise_out)}});
    return;
  }
  std::printf("scene        %s, env %s (%s lookup), view %s\n", desc.name.c_str(),
              env_file.stem().string().c_str(), o.env_lookup.c_str(),
              scene_view(desc, o.view).name.c_str());
  std::printf("image        %d x %d, %zu hit pixels, %d samples per pixel (seed %llu)\n",
              gbuffer.width, gbuffer.height, gbuffer.hit_count(), ref.samples_per_pixel,
              static_cast<unsigned long long>(o.seed));
  std::printf("rays         %llu in %.2f s (%.1f M rays/s); total %.2f s\n",
              static_cast<unsigned long long>(ref.rays_traced), ref.seconds,
              ref.seconds > 0 ? ref.rays_traced / ref.seconds * 1e-6 : 0.0, seconds);
  std::printf("noise        %.3g (RMS standard error / RMS radiance over the hits)\n", noise);
  std::printf("wrote        %s\n", o.out.c_str());
  std::printf("wrote        %s\n", png.string().c_str());
  if (!o.stderr_out.empty()) std::printf("wrote        %s\n", o.stderr_out.c_str());
  if (!o.hits_out.empty()) std::printf("wrote        %s\n", o.hits_out.c_str());
  if (!o.pointwise_out.empty()) std::printf("wrote        %s\n", o.pointwise_out.c_str());
}

}  // namespace

void add_image_commands(CLI::App& app) {
  CLI::App* image = app.add_subcommand("image", "Image error metrics and reference renders");
  image->require_subcommand(1);

  auto diff = std::make_shared<DiffOptions>();
  CLI::App* d = image->add_subcommand(
      "diff", "Relative L2, RMSE, PSNR and max error of an EXR against a reference EXR");
  d->add_option("image", diff->image, "The image to measure (EXR)")->required();
  d->add_option("reference", diff->reference, "The reference (EXR)")->required();
  d->add_option("--out", diff->out, "Write the false-colour relative error image (PNG)");
  d->add_option("--scale", diff->scale,
                "Relative error at the top of the colour map (0: the 99th percentile)");
  d->add_option("--mask", diff->mask,
                "EXR of the same size: count only pixels whose largest channel is > 0.5");
  d->add_option("--report", diff->report,
                "Write the metrics with provenance as a JSON file (atomically)");
  d->add_flag("--json", diff->json, "Print one JSON object (keys in docs/image-error.md)");
  d->callback([diff] { run_diff(*diff); });

  auto ref = std::make_shared<ReferenceOptions>();
  CLI::App* r = image->add_subcommand(
      "reference",
      "Path-traced reference of the bi-scale model (direct light through the macro visibility "
      "and the BTF; slow, for tiny scenes)");
  r->add_option("scene", ref->scene, "Scene name or .toml path")->required();
  r->add_option("--env", ref->env, "Environment map: a lat-long EXR path or a name")->required();
  r->add_option("--rotate", ref->rotate_deg, "Rotate the environment about +y (degrees)");
  r->add_option("--env-lookup", ref->env_lookup,
                "latlong: the image itself per sample (the true environment); cubemap: the "
                "scene's cubemap (what the bi-scale render sees)")
      ->check(CLI::IsMember({"latlong", "cubemap"}));
  r->add_option("--view", ref->view, "View preset of the scene (default: its first)");
  r->add_option("--eye", ref->eye, "Camera position x,y,z");
  r->add_option("--target", ref->target, "Camera target x,y,z");
  r->add_option("--up", ref->up, "Camera up direction x,y,z");
  r->add_option("--fov", ref->fov, "Vertical field of view, degrees");
  r->add_option("--size", ref->size, "Image size WxH (default 640x480)");
  r->add_option("--samples", ref->samples,
                "Strata per side: samples^2 rays per pixel (even, 2..256; default 32)");
  r->add_option("--seed", ref->seed, "Seed of the stratified jitter (default 1)");
  r->add_option("--filter", ref->filter, "BTF texel filter")
      ->check(CLI::IsMember({"nearest", "bilinear"}));
  r->add_option("--btf-resolution", ref->btf_resolution, "BTF texels per side (as render)")
      ->check(CLI::Range(1, 1024));
  r->add_flag("--no-background", ref->no_background, "Black background");
  r->add_option("--out", ref->out, "Linear radiance (EXR)")->required();
  r->add_option("--png", ref->png, "Tone-mapped PNG (default: --out with .png)");
  r->add_option("--exposure", ref->exposure, "PNG exposure in stops (after auto exposure)");
  r->add_option("--stderr", ref->stderr_out, "Per-pixel standard error of the estimate (EXR)");
  r->add_option("--hits", ref->hits_out,
                "Hit mask (EXR: 1 where the G-buffer hits the mesh), for image diff --mask");
  r->add_option("--pointwise", ref->pointwise_out,
                "Also write the bi-scale model with T computed at every pixel's own hit point "
                "(no vertex interpolation; EXR)");
  r->add_flag("--json", ref->json, "Print one JSON object (keys in docs/image-error.md)");
  r->callback([ref] { run_reference(*ref); });
}

}  // namespace prt::cli
