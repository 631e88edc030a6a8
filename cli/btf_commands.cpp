// `prtlab btf list|generate|info|preview|import|export`: the BTFs prtlab generates from
// meso-structures, and measured ones brought in from and out to the UTIA and Bonn layouts
// (docs/btf.md). Documented in docs/cli.md (every option and JSON key).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "prtlab/base/error.h"
#include "prtlab/btf/btf.h"
#include "prtlab/btf/btf_generator.h"
#include "prtlab/btf/btf_materials.h"
#include "prtlab/btf/measured_btf.h"
#include "prtlab/btf/ubo_btf.h"
#include "prtlab/btf/utia_btf.h"
#include "prtlab/image/image_io.h"
#include "prtlab/sphere/hemisphere_grid.h"

namespace prt::cli {
namespace {

nlohmann::json rgb_json(const Rgb& v) {
  return nlohmann::json::array({v.x, v.y, v.z});
}

std::string rgb_text(const Rgb& v) {
  return fmt::format("{:.4g} {:.4g} {:.4g}", v.x, v.y, v.z);
}

// Options shared by every command that may have to generate a BTF.
struct GenerateOptions {
  int resolution = 32;
  int views = 12;
  int lights = 8;
  int supersampling = 2;
  int interreflection = 0;
  int grid = 0;
  bool force = false;

  BtfParams params() const {
    BtfParams p;
    p.resolution = resolution;
    p.view_side = views;
    p.light_side = lights;
    p.supersampling = supersampling;
    p.interreflection_samples = interreflection;
    p.geometry_grid = grid;
    return p;
  }
};

void add_generate_options(CLI::App* cmd, GenerateOptions& o) {
  cmd->add_option("--res", o.resolution, "Texels per side U")
      ->capture_default_str()
      ->check(CLI::Range(1, 1024));
  cmd->add_option("--views", o.views, "View grid side (V = views^2 directions)")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  cmd->add_option("--lights", o.lights, "Light grid side S (M = S^2; the scene's local_grid)")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  cmd->add_option("--supersampling", o.supersampling, "Points per texel side")
      ->capture_default_str()
      ->check(CLI::Range(1, 8));
  cmd->add_option("--interreflection", o.interreflection,
                  "Rays per point for one bounce of interreflection (0: off)")
      ->capture_default_str()
      ->check(CLI::Range(0, 1024));
  cmd->add_option("--grid", o.grid, "Height-field cells per side (0: max(128, 4 U))")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));
  cmd->add_flag("--force", o.force, "Regenerate even when the stage cache holds the BTF");
}

struct Loaded {
  Btf btf;
  std::string source;  ///< "file", "cache" or "generated"
  std::filesystem::path file;
  double seconds = 0;
  double generate_seconds = 0;
  std::string key;
};

// A material name is generated (through the stage cache); anything else must be a BTF file.
Loaded load_or_generate(const std::string& what, const GenerateOptions& o) {
  Loaded out;
  if (!is_btf_material(what)) {
    if (!std::filesystem::exists(what)) {
      std::string valid;
      for (const auto& n : btf_material_names()) valid += (valid.empty() ? "" : ", ") + n;
      throw ParameterError(
          fmt::format("'{}' is neither a BTF material ({}) nor an existing BTF file", what, valid));
    }
    const auto t0 = std::chrono::steady_clock::now();
    out.btf = read_btf(what);
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    out.source = "file";
    out.file = what;
    return out;
  }
  StageCache cache;
  auto r =
      generate_btf_cached(what, o.params(), cache, o.force ? CacheMode::kRefresh : CacheMode::kUse,
                          !global_options().quiet);
  out.btf = std::move(r.btf);
  out.source = r.cache_hit ? "cache" : "generated";
  out.file = r.cache_file;
  out.seconds = r.seconds;
  out.generate_seconds = r.generate_seconds;
  out.key = r.key.hex();
  return out;
}

nlohmann::json stats_json(const Btf& b, const BtfStats& s) {
  return {{"material", b.material()},
          {"resolution", b.resolution()},
          {"view_side", b.view_side()},
          {"views", b.view_count()},
          {"light_side", b.light_side()},
          {"lights", b.light_count()},
          {"bytes", b.bytes()},
          {"megabytes", static_cast<double>(b.bytes()) / 1e6},
          {"min", rgb_json(s.min)},
          {"max", rgb_json(s.max)},
          {"mean", rgb_json(s.mean)},
          {"albedo_mean", rgb_json(s.albedo_mean)},
          {"albedo_max", rgb_json(s.albedo_max)},
          {"view_independent", b.view_independent()},
          {"non_finite", s.non_finite},
          {"parameters", b.parameters()}};
}

void print_stats(const Btf& b, const BtfStats& s) {
  std::printf("material        %s\n", b.material().c_str());
  std::printf("size            %d x %d texels x %d views (%d^2) x %d lights (%d^2) x RGB float\n",
              b.resolution(), b.resolution(), b.view_count(), b.view_side(), b.light_count(),
              b.light_side());
  std::printf("bytes           %.1f MB\n", static_cast<double>(b.bytes()) / 1e6);
  std::printf("min             %s\n", rgb_text(s.min).c_str());
  std::printf("max             %s\n", rgb_text(s.max).c_str());
  std::printf("mean            %s\n", rgb_text(s.mean).c_str());
  std::printf("albedo mean     %s   (directional albedo averaged over lights)\n",
              rgb_text(s.albedo_mean).c_str());
  std::printf("albedo max      %s   (largest over lights; <= 1 without interreflection)\n",
              rgb_text(s.albedo_max).c_str());
  std::printf("view dependent  %s\n", b.view_independent() ? "no (Lambertian)" : "yes");
  if (s.non_finite) std::printf("non-finite      %zu values\n", s.non_finite);
}

// --- list -----------------------------------------------------------------------------------

void run_list(bool json) {
  if (json) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& n : btf_material_names())
      list.push_back({{"name", n}, {"description", btf_material_description(n)}});
    print_json({{"materials", list}});
    return;
  }
  for (const auto& n : btf_material_names())
    std::printf("%-9s %s\n", n.c_str(), btf_material_description(n).c_str());
}

// --- generate -------------------------------------------------------------------------------

struct GenerateCli {
  std::string material;
  GenerateOptions gen;
  std::string out;
  bool json = false;
};

void run_generate(const GenerateCli& o) {
  if (!is_btf_material(o.material))
    throw ParameterError(fmt::format("unknown BTF material '{}' (valid: {})", o.material,
                                     fmt::join(btf_material_names(), ", ")));
  const Loaded l = load_or_generate(o.material, o.gen);
  if (!o.out.empty()) write_btf(l.btf, o.out);
  const BtfStats s = btf_stats(l.btf);
  if (o.json) {
    nlohmann::json j = stats_json(l.btf, s);
    j["cache_hit"] = l.source == "cache";
    j["cache_file"] = l.file.string();
    j["cache_key"] = l.key;
    j["seconds"] = l.seconds;
    j["generate_seconds"] = l.generate_seconds;
    j["out"] = o.out.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.out);
    print_json(std::move(j));
    return;
  }
  print_stats(l.btf, s);
  if (l.source == "cache")
    std::printf("loaded          %.2f s  (cache hit)\n", l.seconds);
  else
    std::printf("generated       %.2f s ray tracing, %.2f s with storing and reloading\n",
                l.generate_seconds, l.seconds);
  std::printf("cache file      %s\n", l.file.string().c_str());
  if (!o.out.empty()) std::printf("wrote           %s\n", o.out.c_str());
}

// --- info -----------------------------------------------------------------------------------

struct InfoCli {
  std::string input;
  GenerateOptions gen;
  bool json = false;
};

void run_info(const InfoCli& o) {
  const Loaded l = load_or_generate(o.input, o.gen);
  const BtfStats s = btf_stats(l.btf);
  if (o.json) {
    nlohmann::json j = stats_json(l.btf, s);
    j["source"] = l.source;
    j["file"] = l.file.string();
    nlohmann::json albedo = nlohmann::json::array();
    for (const Rgb& a : s.albedo) albedo.push_back(rgb_json(a));
    j["albedo_per_light"] = albedo;
    print_json(std::move(j));
    return;
  }
  print_stats(l.btf, s);
  std::printf("source          %s (%s)\n", l.source.c_str(), l.file.string().c_str());
}

// --- preview --------------------------------------------------------------------------------

struct PreviewCli {
  std::string input;
  GenerateOptions gen;
  std::string out;
  double exposure = 0.0;
  bool json = false;
};

Vec3d polar_direction(double theta_deg, double phi_deg) {
  const double t = theta_deg * kPi / 180.0, p = phi_deg * kPi / 180.0;
  return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

struct Angles {
  double theta, phi;
};
// Rows: views from the zenith, 45 and 70 degrees towards +x. Columns: lights from the zenith,
// 45 degrees from -x (the mirror direction of the 45-degree view: highlights), 60 degrees from
// +y and 75 degrees from -x (long shadows).
constexpr Angles kPreviewViews[] = {{0, 0}, {45, 0}, {70, 0}};
constexpr Angles kPreviewLights[] = {{0, 0}, {45, 180}, {60, 90}, {75, 180}};

void run_preview(const PreviewCli& o) {
  const Loaded l = load_or_generate(o.input, o.gen);
  const Btf& b = l.btf;
  const HemisphereGrid vg(b.view_side()), lg(b.light_side());
  const int u = b.resolution();
  const int scale = std::max(1, static_cast<int>(std::lround(96.0 / u)));
  const int panel = 2 * u * scale;  // 2 x 2 tiles, so seams in the tiling would show
  const int gap = 4;
  const int rows = static_cast<int>(std::size(kPreviewViews));
  const int cols = static_cast<int>(std::size(kPreviewLights));
  RgbImage img(cols * panel + (cols + 1) * gap, rows * panel + (rows + 1) * gap);
  std::fill(img.pixels.begin(), img.pixels.end(), Rgb(0.0f));
  nlohmann::json panels = nlohmann::json::array();
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const Vec3d vd = polar_direction(kPreviewViews[r].theta, kPreviewViews[r].phi);
      const Vec3d ld = polar_direction(kPreviewLights[c].theta, kPreviewLights[c].phi);
      // The sample nearest to the wanted direction (cell_of finds the cell containing it).
      const int view = vg.cell_of(vd), light = lg.cell_of(ld);
      const Vec3d va = vg.direction(view), la = lg.direction(light);
      panels.push_back({{"row", r},
                        {"column", c},
                        {"view", view},
                        {"light", light},
                        {"view_theta_deg", std::acos(va.z) * 180.0 / kPi},
                        {"view_phi_deg", std::atan2(va.y, va.x) * 180.0 / kPi},
                        {"light_theta_deg", std::acos(la.z) * 180.0 / kPi},
                        {"light_phi_deg", std::atan2(la.y, la.x) * 180.0 / kPi}});
      const int x0 = gap + c * (panel + gap), y0 = gap + r * (panel + gap);
      for (int py = 0; py < panel; ++py) {
        // v grows upwards in the picture, so it shows the tile as seen from above (+x right).
        const int ty = (panel - 1 - py) / scale % u;
        for (int px = 0; px < panel; ++px) {
          const int tx = px / scale % u;
          img.at(x0 + px, y0 + py) = b.value(ty * u + tx, view, light);
        }
      }
    }
  }
  ToneMap tm;
  tm.exposure = o.exposure;
  write_png(img, o.out, tm);
  if (o.json) {
    print_json({{"material", b.material()},
                {"source", l.source},
                {"out", o.out},
                {"width", img.width},
                {"height", img.height},
                {"panels", panels}});
    return;
  }
  std::printf(
      "wrote %s (%d x %d): rows = views at 0/45/70 deg towards +x, columns = lights "
      "at 0 deg, 45 deg from -x, 60 deg from +y, 75 deg from -x; 2 x 2 tiles each\n",
      o.out.c_str(), img.width, img.height);
}

// --- import / export ------------------------------------------------------------------------

struct ImportCli {
  std::string input;
  std::string format;
  MeasuredImportOptions options;
  std::string cosine = "cell-mean";
  std::string out;
  bool json = false;
};

void run_import(const ImportCli& o) {
  MeasuredImportOptions opt = o.options;
  opt.cosine = parse_light_cosine(o.cosine);
  const auto t0 = std::chrono::steady_clock::now();
  MeasuredBtf m;
  if (o.format == "utia")
    m = read_utia_btf(o.input, opt);
  else if (o.format == "ubo")
    m = read_ubo_btf(o.input, opt);
  else
    throw ParameterError(fmt::format("unknown import format '{}' (valid: utia, ubo)", o.format));
  write_btf(m.btf, o.out);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const MeasuredCoverage& c = m.coverage;
  const BtfStats s = btf_stats(m.btf);
  if (o.json) {
    nlohmann::json j = stats_json(m.btf, s);
    j["format"] = o.format;
    j["input"] = o.input;
    j["out"] = o.out;
    j["coverage"] = c.to_json();
    j["seconds"] = seconds;
    print_json(std::move(j));
    return;
  }
  print_stats(m.btf, s);
  std::printf("measured        %d x %d texels x %d views x %d lights (box filter %d x %d)\n",
              c.measured_resolution, c.measured_resolution, c.measured_views, c.measured_lights,
              c.box_factor, c.box_factor);
  std::printf("views used      %d of %d measured; nearest %.2f deg mean, %.2f deg max\n",
              c.views_used, c.measured_views, c.mean_view_angle_deg, c.max_view_angle_deg);
  std::printf("lights used     %d of %d measured; nearest %.2f deg mean, %.2f deg max\n",
              c.lights_used, c.measured_lights, c.mean_light_angle_deg, c.max_light_angle_deg);
  std::printf("wrote           %s (%.2f s)\n", o.out.c_str(), seconds);
}

struct ExportCli {
  std::string input;
  GenerateOptions gen;
  std::string format;
  std::string cosine = "cell-mean";
  bool png = false;
  double png_scale = 1.0;
  int components = 0;
  int scalar_bytes = 4;
  std::string out;
  bool json = false;
};

void run_export(const ExportCli& o) {
  const LightCosine cosine = parse_light_cosine(o.cosine);
  const Loaded l = load_or_generate(o.input, o.gen);
  nlohmann::json j = {{"material", l.btf.material()},
                      {"source", l.source},
                      {"format", o.format},
                      {"out", o.out},
                      {"light_cosine", o.cosine}};
  if (o.format == "utia") {
    UtiaWriteOptions w;
    w.format = o.png ? UtiaImageFormat::kPng16 : UtiaImageFormat::kExr;
    w.png_scale = o.png_scale;
    w.cosine = cosine;
    const UtiaWriteReport r = write_utia_btf(l.btf, o.out, w);
    j["images"] = r.images;
    j["clipped"] = r.clipped;
  } else if (o.format == "ubo-fmf" || o.format == "ubo-bdi") {
    UboWriteOptions w;
    w.components = o.components;
    w.scalar_bytes = o.scalar_bytes;
    w.cosine = cosine;
    if (o.format == "ubo-fmf")
      write_ubo_fmf(l.btf, o.out, w);
    else
      write_ubo_bdi(l.btf, o.out, w);
    j["bytes"] = std::filesystem::file_size(o.out);
  } else {
    throw ParameterError(
        fmt::format("unknown export format '{}' (valid: utia, ubo-fmf, ubo-bdi)", o.format));
  }
  if (o.json) {
    print_json(std::move(j));
    return;
  }
  std::printf("wrote %s (%s", o.out.c_str(), o.format.c_str());
  if (j.contains("images")) {
    std::printf(", %d images", j["images"].get<int>());
    if (j["clipped"].get<std::size_t>() > 0)
      std::printf(", %zu PNG samples clipped: raise --png-scale", j["clipped"].get<std::size_t>());
  } else {
    std::printf(", %zu bytes", j["bytes"].get<std::size_t>());
  }
  std::printf(") from %s (%s)\n", l.btf.material().c_str(), l.source.c_str());
}

}  // namespace

void add_btf_commands(CLI::App& app) {
  CLI::App* btf = app.add_subcommand(
      "btf",
      "BTFs generated from meso-structures or measured: list, generate, inspect, import, export");
  btf->require_subcommand(1);

  auto list_json = std::make_shared<bool>(false);
  CLI::App* list_cmd = btf->add_subcommand("list", "List the built-in BTF materials");
  list_cmd->add_flag("--json", *list_json, "Print one JSON object (keys in docs/cli.md)");
  list_cmd->callback([list_json] { run_list(*list_json); });

  auto gen = std::make_shared<GenerateCli>();
  CLI::App* gen_cmd = btf->add_subcommand(
      "generate", "Ray trace a material's meso-structure into a BTF (stage-cached)");
  gen_cmd->add_option("material", gen->material, "Material name (prtlab btf list)")->required();
  add_generate_options(gen_cmd, gen->gen);
  gen_cmd->add_option("--out", gen->out, "Also write the BTF archive to this file");
  gen_cmd->add_flag("--json", gen->json, "Print one JSON object (keys in docs/cli.md)");
  gen_cmd->callback([gen] { run_generate(*gen); });

  auto info = std::make_shared<InfoCli>();
  CLI::App* info_cmd =
      btf->add_subcommand("info", "Size, value range and albedo of a BTF (material or file)");
  info_cmd
      ->add_option("btf", info->input,
                   "Material name (generated or taken from the cache) or a BTF archive file")
      ->required();
  add_generate_options(info_cmd, info->gen);
  info_cmd->add_flag("--json", info->json, "Print one JSON object (keys in docs/cli.md)");
  info_cmd->callback([info] { run_info(*info); });

  auto prev = std::make_shared<PreviewCli>();
  CLI::App* prev_cmd =
      btf->add_subcommand("preview", "Tone-mapped PNG of texel images for a few view/light pairs");
  prev_cmd
      ->add_option("btf", prev->input,
                   "Material name (generated or taken from the cache) or a BTF archive file")
      ->required();
  add_generate_options(prev_cmd, prev->gen);
  prev_cmd->add_option("--out", prev->out, "Output PNG")->required();
  prev_cmd->add_option("--exposure", prev->exposure, "Stops added after auto exposure")
      ->capture_default_str();
  prev_cmd->add_flag("--json", prev->json, "Print one JSON object (keys in docs/cli.md)");
  prev_cmd->callback([prev] { run_preview(*prev); });

  auto imp = std::make_shared<ImportCli>();
  CLI::App* imp_cmd = btf->add_subcommand(
      "import", "Resample a measured BTF (UTIA image directory, Bonn UBO file) into a BTF archive");
  imp_cmd->add_option("path", imp->input, "UTIA directory or UBO .btf file")->required();
  imp_cmd->add_option("--format", imp->format, "utia or ubo")
      ->required()
      ->check(CLI::IsMember({"utia", "ubo"}));
  imp_cmd->add_option("--view-side", imp->options.view_side, "View grid side (V = n^2)")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  imp_cmd->add_option("--light-side", imp->options.light_side, "Light grid side S (M = S^2)")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  imp_cmd
      ->add_option("--resolution", imp->options.resolution,
                   "Texels per side U; must divide the measured size (0: the measured size)")
      ->capture_default_str()
      ->check(CLI::Range(0, 65536));
  imp_cmd->add_option("--scale", imp->options.scale, "Multiplies every value")
      ->capture_default_str();
  imp_cmd
      ->add_option("--light-cosine", imp->cosine,
                   "cell-mean: convert to prtlab's cell-mean cosine; as-stored: keep the values")
      ->capture_default_str()
      ->check(CLI::IsMember({"cell-mean", "as-stored"}));
  imp_cmd->add_option("--material", imp->options.material,
                      "Material name stored in the archive (default: utia:<dir> / ubo:<stem>)");
  imp_cmd->add_option("--out", imp->out, "BTF archive to write")->required();
  imp_cmd->add_flag("--json", imp->json, "Print one JSON object (keys in docs/cli.md)");
  imp_cmd->callback([imp] { run_import(*imp); });

  auto exp_cli = std::make_shared<ExportCli>();
  CLI::App* exp_cmd = btf->add_subcommand(
      "export", "Write a BTF (material or file) as a UTIA image directory or a Bonn UBO file");
  exp_cmd
      ->add_option("btf", exp_cli->input,
                   "Material name (generated or taken from the cache) or a BTF archive file")
      ->required();
  add_generate_options(exp_cmd, exp_cli->gen);
  exp_cmd->add_option("--format", exp_cli->format, "utia, ubo-fmf or ubo-bdi")
      ->required()
      ->check(CLI::IsMember({"utia", "ubo-fmf", "ubo-bdi"}));
  exp_cmd
      ->add_option("--light-cosine", exp_cli->cosine,
                   "cell-mean (undo prtlab's cell-mean cosine) or as-stored (write the values)")
      ->capture_default_str()
      ->check(CLI::IsMember({"cell-mean", "as-stored"}));
  exp_cmd->add_flag("--png", exp_cli->png, "utia: 16-bit PNG images instead of float EXR");
  exp_cmd->add_option("--png-scale", exp_cli->png_scale, "utia --png: the value of a 65535 sample")
      ->capture_default_str();
  exp_cmd
      ->add_option("--components", exp_cli->components,
                   "ubo-fmf: rank of the truncated SVD (0: exact, no truncation)")
      ->capture_default_str()
      ->check(CLI::Range(0, 1 << 30));
  exp_cmd->add_option("--scalar-bytes", exp_cli->scalar_bytes, "ubo-fmf: 4 (float) or 2 (half)")
      ->capture_default_str()
      ->check(CLI::IsMember({2, 4}));
  exp_cmd->add_option("--out", exp_cli->out, "Output directory (utia) or file (ubo-*)")->required();
  exp_cmd->add_flag("--json", exp_cli->json, "Print one JSON object (keys in docs/cli.md)");
  exp_cmd->callback([exp_cli] { run_export(*exp_cli); });
}

}  // namespace prt::cli
