// `prtlab env info` and `prtlab env cubemap`: inspect a lat-long EXR and resample it onto the
// cubemap basis. Documented in docs/cli.md (every option and JSON key).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string>

#include "commands.h"
#include "prtlab/base/log.h"
#include "prtlab/base/named_warning.h"
#include "prtlab/image/image_io.h"
#include "prtlab/lighting/environment_map.h"
#include "prtlab/lighting/srbf_light.h"
#include "prtlab/storage/atomic_file.h"
#include "prtlab/storage/data_paths.h"

namespace prt::cli {
namespace {

nlohmann::json rgb_json(const Vec3d& v) {
  return nlohmann::json::array({v.x, v.y, v.z});
}

struct EnvStats {
  Vec3d min{std::numeric_limits<double>::infinity()};
  Vec3d max{-std::numeric_limits<double>::infinity()};
  Vec3d mean{0.0};   ///< solid-angle weighted: power / 4 pi
  Vec3d power{0.0};  ///< integral of radiance over the sphere
};

EnvStats env_stats(const LatLongImage& image) {
  EnvStats s;
  for (const Rgb& t : image.texels) {
    s.min = glm::min(s.min, Vec3d(t));
    s.max = glm::max(s.max, Vec3d(t));
  }
  s.power = image.total_power();
  s.mean = s.power / kFourPi;
  return s;
}

double dynamic_range(const LatLongImage& image) {
  float lo = std::numeric_limits<float>::infinity(), hi = 0.f;
  for (const Rgb& t : image.texels)
    for (int c = 0; c < 3; ++c) {
      if (t[c] > 0.f) lo = std::min(lo, t[c]);
      hi = std::max(hi, t[c]);
    }
  return hi > 0.f ? static_cast<double>(hi) / lo : 0.0;
}

std::string rgb_text(const Vec3d& v) {
  return fmt::format("{:.6g} {:.6g} {:.6g}", v.x, v.y, v.z);
}

Vec3d relative_difference(const Vec3d& after, const Vec3d& before) {
  Vec3d d{0.0};
  for (int c = 0; c < 3; ++c)
    d[c] = before[c] != 0.0 ? (after[c] - before[c]) / before[c] : after[c] - before[c];
  return d;
}

struct InfoOptions {
  std::string input;
  bool json = false;
};

void run_info(const InfoOptions& o) {
  const std::filesystem::path file = resolve_envmap(o.input);
  EnvLoadReport report;
  const LatLongImage image = load_latlong_exr(file, &report);
  const EnvStats s = env_stats(image);
  if (o.json) {
    print_json({{"file", file.string()},
                {"width", image.width},
                {"height", image.height},
                {"min", rgb_json(s.min)},
                {"max", rgb_json(s.max)},
                {"mean", rgb_json(s.mean)},
                {"power", rgb_json(s.power)},
                {"invalid_texels", report.invalid_texels},
                {"aspect_2_to_1", report.aspect_2_to_1},
                {"warnings", named_warning_counts()}});
    return;
  }
  std::printf("file            %s\n", file.string().c_str());
  std::printf("size            %d x %d texels (lat-long)\n", image.width, image.height);
  std::printf("min radiance    %s\n", rgb_text(s.min).c_str());
  std::printf("max radiance    %s\n", rgb_text(s.max).c_str());
  std::printf("mean radiance   %s   (solid-angle weighted)\n", rgb_text(s.mean).c_str());
  std::printf("power           %s   (integral of radiance over the sphere)\n",
              rgb_text(s.power).c_str());
  std::printf("invalid texels  %zu   (NaN, Inf or negative; set to 0)\n", report.invalid_texels);
  std::printf("dynamic range   %.3g   (largest channel value / smallest positive one)\n",
              dynamic_range(image));
  for (const auto& [name, count] : named_warning_counts())
    std::printf("warning         %s (see above)\n", name.c_str());
}

struct CubemapOptions {
  std::string input;
  int resolution = 32;
  std::string out;
  std::string preview;
  bool json = false;
};

void run_cubemap(const CubemapOptions& o) {
  const std::filesystem::path file = resolve_envmap(o.input);
  EnvLoadReport report;
  const LatLongImage image = load_latlong_exr(file, &report);
  const auto t0 = std::chrono::steady_clock::now();
  const Cubemap cubemap = resample_to_cubemap(image, o.resolution);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // The cubemap and its preview together or neither.
  std::vector<PendingFile> files{{o.out, [&](const std::filesystem::path& tmp) {
                                    write_exr(cubemap_strip_image(cubemap), tmp);
                                  }}};
  if (!o.preview.empty())
    files.push_back({o.preview, [&](const std::filesystem::path& tmp) {
                       write_png(cubemap_cross_image(cubemap), tmp);
                     }});
  write_files_atomically(files);

  const Vec3d before = image.total_power(), after = cubemap.total_power();
  const Vec3d rel = relative_difference(after, before);
  if (o.json) {
    print_json(
        {{"file", file.string()},
         {"width", image.width},
         {"height", image.height},
         {"resolution", o.resolution},
         {"out", o.out},
         {"preview", o.preview.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.preview)},
         {"power_latlong", rgb_json(before)},
         {"power_cubemap", rgb_json(after)},
         {"power_relative_difference", rgb_json(rel)},
         {"invalid_texels", report.invalid_texels},
         {"resample_seconds", seconds}});
    return;
  }
  std::printf("input           %s (%d x %d)\n", file.string().c_str(), image.width, image.height);
  std::printf("cubemap         6 x %d x %d = %d pixels, resampled in %.3f s\n", o.resolution,
              o.resolution, cubemap.layout.pixel_count(), seconds);
  std::printf("power lat-long  %s\n", rgb_text(before).c_str());
  std::printf("power cubemap   %s\n", rgb_text(after).c_str());
  std::printf("relative diff   %.3g %.3g %.3g\n", rel.x, rel.y, rel.z);
  std::printf("wrote           %s (6R x R strip, faces +X -X +Y -Y +Z -Z)\n", o.out.c_str());
  if (!o.preview.empty()) std::printf("wrote           %s (cross preview)\n", o.preview.c_str());
}

struct FitSrbfOptions {
  std::string input;
  int count = 162;
  int resolution = 32;
  int rounds = 40;
  std::string seeding = "coverage";
  std::string out;
  std::string preview;
  bool json = false;
};

nlohmann::json srbf_json(const SrbfLight& f) {
  nlohmann::json list = nlohmann::json::array();
  for (std::size_t j = 0; j < f.count(); ++j)
    list.push_back({{"centre", rgb_json(f.centres[j])},
                    {"bandwidth", f.bandwidths[j]},
                    {"coefficient", rgb_json(f.coefficients[j])}});
  return {{"kernel", std::string(to_string(f.kernel))},
          {"scattered", f.scattered},
          {"count", f.count()},
          {"parameters", f.parameter_count()},
          {"srbfs", std::move(list)}};
}

// Two cube-map crosses one above the other: the fit, then the light it approximates.
RgbImage stacked_crosses(const Cubemap& top, const Cubemap& bottom) {
  const RgbImage a = cubemap_cross_image(top), b = cubemap_cross_image(bottom);
  RgbImage out(a.width, a.height + b.height);
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) out.at(x, y) = a.at(x, y);
  for (int y = 0; y < b.height; ++y)
    for (int x = 0; x < b.width; ++x) out.at(x, a.height + y) = b.at(x, y);
  return out;
}

void run_fit_srbf(const FitSrbfOptions& o) {
  const std::filesystem::path file = resolve_envmap(o.input);
  const LatLongImage image = load_latlong_exr(file);
  const Cubemap light = resample_to_cubemap(image, o.resolution);
  // A map without energy (all black, or every texel invalid and zeroed) has no relative error
  // to fit: refused, naming the map, instead of a "perfect" 0 / 0.
  double energy = 0;
  for (const Rgb& v : light.radiance) energy += static_cast<double>(v.x) + v.y + v.z;
  if (!(energy > 0))
    throw InputError(file,
                     "the map has no energy (every texel is zero or invalid): there is "
                     "nothing to fit, and a relative error against it is undefined");
  ScatteredFitOptions so;
  so.count = o.count;
  so.rounds = o.rounds;
  so.seeding = o.seeding == "coverage" ? SrbfSeeding::kCoverage : SrbfSeeding::kResidual;
  so.on_round = [](int round, double e) {
    log_info("fit-srbf: round {}: relative error {:.5f}", round, e);
  };
  const auto t0 = std::chrono::steady_clock::now();
  ScatteredFitReport report;
  const SrbfLight fit = fit_scattered_srbf(light, so, &report);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // Uniform SRBFs with the same number of parameters: 3 per SRBF instead of 6.
  const int uniform_count = static_cast<int>(fit.parameter_count() / 3);
  const SrbfLight uniform = fit_uniform_srbf(light, uniform_count);
  const double uniform_error = srbf_relative_error(uniform, light);
  nlohmann::json j = {{"file", file.string()},
                      {"resolution", o.resolution},
                      {"seeding", o.seeding},
                      {"rounds", report.rounds},
                      {"lbfgs_line_search_failures", report.lbfgs_failures},
                      {"seconds", seconds},
                      {"initial_relative_error", report.initial_error},
                      {"relative_error", report.error},
                      {"uniform_count", uniform_count},
                      {"uniform_bandwidth", uniform.bandwidths.front()},
                      {"uniform_relative_error", uniform_error},
                      {"fit", srbf_json(fit)},
                      {"provenance", provenance()}};
  std::vector<PendingFile> files;
  const std::string text = j.dump(2) + "\n";
  if (!o.out.empty())
    files.push_back(
        {o.out, [&](const std::filesystem::path& tmp) { write_text_atomically(tmp, text); }});
  if (!o.preview.empty())
    files.push_back({o.preview, [&](const std::filesystem::path& tmp) {
                       write_png(stacked_crosses(fit.to_cubemap(o.resolution), light), tmp);
                     }});
  write_files_atomically(files);
  if (o.json) {
    j.erase("fit");
    j["out"] = o.out.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.out);
    j["preview"] = o.preview.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.preview);
    print_json(std::move(j));
    return;
  }
  std::printf("input           %s, cubemap R = %d\n", file.string().c_str(), o.resolution);
  std::printf(
      "scattered       %d Gaussian SRBFs (%zu parameters), %s seeding, %d rounds in %.1f s\n",
      o.count, fit.parameter_count(), o.seeding.c_str(), report.rounds, seconds);
  std::printf("error           relative L2 %.5f (initial guess %.5f)\n", report.error,
              report.initial_error);
  std::printf(
      "uniform         %d Gaussian SRBFs (%zu parameters, bandwidth %.1f): relative L2 %.5f\n",
      uniform_count, uniform.parameter_count(), uniform.bandwidths.front(), uniform_error);
  if (!o.out.empty()) std::printf("wrote           %s\n", o.out.c_str());
  if (!o.preview.empty())
    std::printf("wrote           %s (top: the fit, bottom: the light, cube-map crosses)\n",
                o.preview.c_str());
}
}  // namespace

void add_env_commands(CLI::App& app) {
  CLI::App* env = app.add_subcommand("env", "Environment maps: inspect and resample");
  env->require_subcommand(1);

  auto info = std::make_shared<InfoOptions>();
  CLI::App* info_cmd = env->add_subcommand(
      "info",
      "Print size, min/max/mean radiance, total power and invalid texels of a lat-long EXR");
  info_cmd
      ->add_option("exr", info->input,
                   "Lat-long EXR: a path, or a name from the data cache (e.g. courtyard)")
      ->required();
  info_cmd->add_flag("--json", info->json, "Print one JSON object (keys in docs/cli.md)");
  info_cmd->callback([info] { run_info(*info); });

  auto cube = std::make_shared<CubemapOptions>();
  CLI::App* cube_cmd = env->add_subcommand(
      "cubemap", "Resample a lat-long EXR onto a 6 x R x R cubemap (exact texel/pixel overlaps)");
  cube_cmd
      ->add_option("exr", cube->input,
                   "Lat-long EXR: a path, or a name from the data cache (e.g. courtyard)")
      ->required();
  cube_cmd->add_option("--res", cube->resolution, "Cubemap face resolution R")
      ->capture_default_str()
      ->check(CLI::Range(1, 8192));
  cube_cmd->add_option("--out", cube->out, "Output EXR: the faces side by side, 6R x R, float RGB")
      ->required();
  cube_cmd->add_option("--preview", cube->preview,
                       "Also write a tone-mapped PNG of the faces as a cross (4R x 3R)");
  cube_cmd->add_flag("--json", cube->json, "Print one JSON object (keys in docs/cli.md)");
  cube_cmd->callback([cube] { run_cubemap(*cube); });

  auto fit = std::make_shared<FitSrbfOptions>();
  CLI::App* fit_cmd = env->add_subcommand(
      "fit-srbf",
      "Fit scattered Gaussian SRBFs to an environment (Tsai and Shih 2006, section 5.3) and "
      "compare with uniform SRBFs of the same parameter count");
  fit_cmd
      ->add_option("exr", fit->input,
                   "Lat-long EXR: a path, or a name from the data cache (e.g. courtyard)")
      ->required();
  fit_cmd->add_option("--count", fit->count, "Scattered SRBFs (6 parameters each)")
      ->capture_default_str()
      ->check(CLI::Range(1, 4096));
  fit_cmd->add_option("--res", fit->resolution, "Cubemap face resolution R of the fit")
      ->capture_default_str()
      ->check(CLI::Range(2, 128));
  fit_cmd
      ->add_option("--rounds", fit->rounds,
                   "Alternating rounds (centres, bandwidths, coefficients) at most")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000));
  fit_cmd
      ->add_option("--seeding", fit->seeding,
                   "Initial centres: coverage (the paper's) or residual (greedy)")
      ->capture_default_str()
      ->check(CLI::IsMember({"coverage", "residual"}));
  fit_cmd->add_option(
      "--out", fit->out,
      "Write the fit (centres, bandwidths, RGB coefficients, errors, provenance) as JSON");
  fit_cmd->add_option("--preview", fit->preview,
                      "Write a PNG: the fit's cube-map cross above the light's");
  fit_cmd->add_flag("--json", fit->json, "Print one JSON object (keys in docs/cli.md)");
  fit_cmd->callback([fit] { run_fit_srbf(*fit); });
}

}  // namespace prt::cli
