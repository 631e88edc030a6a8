#include "material_table.h"

#include <fmt/format.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <toml++/toml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>

#include "experiment_spec.h"
#include "provenance.h"
#include "prtlab/base/error.h"
#include "prtlab/btf/btf_generator.h"
#include "prtlab/btf/btf_materials.h"
#include "prtlab/compress/backend_input.h"
#include "prtlab/compress/compression_stage.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/material_error.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/geometry/scene.h"
#include "prtlab/image/image_io.h"
#include "prtlab/image/ssim.h"
#include "prtlab/render/factored_material.h"
#include "prtlab/render/frame_renderer.h"
#include "prtlab/render/image_error.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/storage/atomic_file.h"
#include "prtlab/storage/data_paths.h"
#include "prtlab/storage/stage_cache.h"
#include "scene_bench.h"

namespace prt::experiments {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

struct MaterialConfig {
  std::string label, backend;
  std::map<std::string, std::string> params;
};

struct TableSpec {
  std::string name, title;
  std::vector<std::string> btfs;
  int resolution = 64, view_side = 8, light_side = 8;
  std::vector<MaterialConfig> materials;
  std::vector<double> tile_polar_deg = {0, 45, 75};
  std::string scene = "bunny", image_btf, environment = "courtyard";
  int width = 320, height = 240;
  std::map<std::string, std::string> paper;
  std::string paper_source;
  std::string notes;  ///< markdown: why ours differ from the paper's, what the numbers show
};

toml::table read_toml(const fs::path& file) {
  try {
    return toml::parse_file(file.string());
  } catch (const toml::parse_error& e) {
    throw InputError(file, fmt::format("line {}: {}", e.source().begin.line, e.description()));
  }
}

TableSpec parse_table(const fs::path& file, const std::string& variant) {
  toml::table t = read_toml(file);
  if (!variant.empty()) {
    const auto* v = t["variant"][variant].as_table();
    if (!v) throw InputError(file, fmt::format("no [variant.{}] table", variant));
    for (const auto& [k, value] : *v) t.insert_or_assign(k, value);
  }
  const auto fail = [&](const std::string& problem) { return InputError(file, problem); };
  static const std::vector<std::string> known = {
      "name",      "title",          "kind",  "btfs",  "resolution",   "view_side", "light_side",
      "materials", "tile_polar_deg", "image", "paper", "paper_source", "notes",     "variant"};
  for (const auto& [k, value] : t)
    if (std::find(known.begin(), known.end(), std::string(k.str())) == known.end())
      throw fail(fmt::format("unknown key '{}' (known: {})", k.str(), fmt::join(known, ", ")));
  TableSpec s;
  s.name = t["name"].value_or(std::string());
  s.title = t["title"].value_or(s.name);
  if (s.name.empty()) throw fail("no name");
  if (t["kind"].value_or(std::string()) != "material_table")
    throw fail("kind is not 'material_table'");
  const auto* btfs = t["btfs"].as_array();
  if (!btfs || btfs->empty()) throw fail("btfs: a non-empty list of BTF names");
  for (const auto& b : *btfs) {
    const std::string n = b.value_or(std::string());
    if (!is_btf_material(n))
      throw fail(
          fmt::format("btfs: '{}' is not a BTF ({})", n, fmt::join(btf_material_names(), ", ")));
    s.btfs.push_back(n);
  }
  s.resolution = t["resolution"].value_or(s.resolution);
  s.view_side = t["view_side"].value_or(s.view_side);
  s.light_side = t["light_side"].value_or(s.light_side);
  if (s.resolution < 1 || s.resolution > 512 || s.view_side < 1 || s.view_side > 32 ||
      s.light_side < 1 || s.light_side > 32)
    throw fail("resolution 1..512, view_side and light_side 1..32");
  const auto* mats = t["materials"].as_array();
  if (!mats || mats->empty()) throw fail("materials: a non-empty array of tables");
  for (const auto& m : *mats) {
    const auto* mt = m.as_table();
    if (!mt) throw fail("materials: each entry is a table {label, backend, params}");
    MaterialConfig c;
    c.backend = (*mt)["backend"].value_or(std::string());
    c.label = (*mt)["label"].value_or(c.backend);
    // Labels name image files.
    if (c.label.empty() || c.label == "full" ||
        c.label.find_first_not_of(
            "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") !=
            std::string::npos)
      throw fail(
          fmt::format("materials: label '{}' must be letters, digits, '_' or '-' (and not "
                      "'full')",
                      c.label));
    for (const MaterialConfig& other : s.materials)
      if (other.label == c.label)
        throw fail(fmt::format("materials: label '{}' is used twice", c.label));
    if (!MaterialRegistry::instance().contains(c.backend))
      throw fail(fmt::format("materials: unknown material backend '{}' ({})", c.backend,
                             fmt::join(MaterialRegistry::instance().names(), ", ")));
    if (const auto* p = (*mt)["params"].as_table())
      for (const auto& [k, v] : *p) {
        std::string value;
        if (v.is_string())
          value = *v.value<std::string>();
        else if (v.is_boolean())
          value = *v.value<bool>() ? "true" : "false";
        else if (v.is_integer())
          value = std::to_string(*v.value<std::int64_t>());
        else if (v.is_floating_point())
          value = fmt::format("{}", *v.value<double>());
        else
          throw fail(
              fmt::format("materials.{}.params.{}: a string, number or bool", c.label, k.str()));
        c.params[std::string(k.str())] = value;
      }
    try {
      (void)MaterialRegistry::instance().create(c.backend, c.params);
    } catch (const ParameterError& e) {
      throw fail(fmt::format("materials '{}': {}", c.label, e.what()));
    }
    s.materials.push_back(std::move(c));
  }
  if (const auto* a = t["tile_polar_deg"].as_array()) {
    s.tile_polar_deg.clear();
    for (const auto& v : *a) {
      const auto deg = v.value<double>();
      if (!deg || *deg < 0 || *deg > 90)
        throw fail("tile_polar_deg: polar angles in degrees, 0 .. 90");
      s.tile_polar_deg.push_back(*deg);
    }
  }
  if (const auto* img = t["image"].as_table()) {
    for (const auto& [k, unused] : *img)
      if (k.str() != "scene" && k.str() != "btf" && k.str() != "environment" &&
          k.str() != "width" && k.str() != "height")
        throw fail(
            fmt::format("image: unknown key '{}' (known: scene, btf, environment, width, "
                        "height; a key meant for the top level must come before the "
                        "first table)",
                        k.str()));
    s.scene = (*img)["scene"].value_or(s.scene);
    s.image_btf = (*img)["btf"].value_or(std::string());
    s.environment = (*img)["environment"].value_or(s.environment);
    s.width = (*img)["width"].value_or(s.width);
    s.height = (*img)["height"].value_or(s.height);
  }
  if (s.image_btf.empty()) s.image_btf = s.btfs.front();
  if (!is_btf_material(s.image_btf))
    throw fail(fmt::format("image.btf: '{}' is not a BTF ({})", s.image_btf,
                           fmt::join(btf_material_names(), ", ")));
  if (const auto* p = t["paper"].as_table())
    for (const auto& [k, v] : *p) s.paper[std::string(k.str())] = v.value_or(std::string());
  s.paper_source = t["paper_source"].value_or(std::string());
  s.notes = t["notes"].value_or(std::string());
  return s;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The light bin nearest each polar angle at azimuth 0.
std::vector<int> tile_lights(int light_side, const std::vector<double>& polar_deg) {
  const HemisphereGrid g(light_side);
  std::vector<int> out;
  for (double deg : polar_deg) {
    const double th = deg * 3.14159265358979323846 / 180.0;
    const Vec3d want(std::sin(th), 0.0, std::cos(th));
    int best = 0;
    for (int j = 1; j < g.cell_count(); ++j)
      if (glm::dot(g.direction(j), want) > glm::dot(g.direction(best), want)) best = j;
    out.push_back(best);
  }
  return out;
}

// The view sample nearest the zenith.
int top_view(int view_side) {
  const HemisphereGrid g(view_side);
  int best = 0;
  for (int v = 1; v < g.cell_count(); ++v)
    if (g.direction(v).z > g.direction(best).z) best = v;
  return best;
}

// Rows: lights; columns: the full BTF, then each material; each tile magnified `zoom` times.
void write_tiles(const Btf& full, const std::vector<std::shared_ptr<const CompressedMaterial>>& ms,
                 const std::vector<int>& lights, const fs::path& file) {
  const int u = full.resolution(), zoom = std::max(1, 96 / u), gap = 4, cell = u * zoom;
  const int cols = 1 + static_cast<int>(ms.size()), rows = static_cast<int>(lights.size());
  RgbImage img(cols * cell + (cols - 1) * gap, rows * cell + (rows - 1) * gap);
  const int view = top_view(full.view_side());
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      for (int y = 0; y < cell; ++y)
        for (int x = 0; x < cell; ++x) {
          const int texel = (u - 1 - y / zoom) * u + x / zoom;
          const Rgb v =
              c == 0 ? full.value(texel, view, lights[r])
                     : ms[static_cast<std::size_t>(c - 1)]->reflectance(texel, view, lights[r]);
          img.pixels[static_cast<std::size_t>(r * (cell + gap) + y) * img.width + c * (cell + gap) +
                     x] = v;
        }
  // One exposure for the whole sheet, from the full BTF's columns.
  std::vector<std::uint8_t> mask(img.pixels.size(), 0);
  for (int r = 0; r < rows; ++r)
    for (int y = 0; y < cell; ++y)
      for (int x = 0; x < cell; ++x)
        mask[static_cast<std::size_t>(r * (cell + gap) + y) * img.width + x] = 1;
  ToneMap tm;
  tm.auto_exposure = false;
  tm.exposure = exposure_of(img, mask);
  write_png(img, file, tm);
}

std::string mb(double bytes) {
  return fmt::format("{:.3f}", bytes / 1e6);
}

json finite_or_null(double x) {
  return std::isfinite(x) ? json(x) : json(nullptr);
}

// A measure of a row or image as text: "-" where it is absent or undefined (null).
std::string number(const json& j, const std::string& key, const char* format) {
  if (!j.contains(key) || !j.at(key).is_number()) return "-";
  return fmt::format(fmt::runtime(format), j.at(key).get<double>());
}

// What each error column means (material_error.h, image/ssim.h), for the README.
const char* kErrorColumns =
    "Errors of the material against the full BTF, over all texels, views, lights and "
    "channels (`core/include/prtlab/compress/material_error.h`), with b the full BTF's value "
    "and d the material's minus b:\n\n"
    "- `rel. L2`: sqrt(sum d^2) / sqrt(sum b^2). The largest values (highlights) dominate it.\n"
    "- `avg. rel. (Suykens)`: the measure of Suykens et al. 2003 (section 4.4, \"average "
    "relative error\", \"up to 100%\" on their checker): the mean of |d| / b over every sample "
    "with b != 0, unguarded as the paper describes it (samples with b = 0 are left out; their "
    "count is `zero_samples` in table.csv). `worst ABRDF` is the largest such mean of one ABRDF "
    "(texel), the paper's \"up to\" read as a maximum over ABRDFs.\n"
    "- `avg. rel. floored`: the same with the denominator max(b, 0.01 m), m the ABRDF "
    "channel's largest value (prtlab's guard, not the paper's): shadowed samples cannot "
    "dominate.\n"
    "- `cos L2`: rel. L2 with each light bin's squared error weighted by its mean cosine c_j. "
    "b already holds c_j once (docs/btf.md), so this counts the cosine twice; it shows how much "
    "of rel. L2 comes from grazing lights.\n"
    "- `white-light L2`: per texel, view and channel, the sum over the light bins of d and of "
    "b (what the material returns under a uniform white environment: every bin has the same "
    "solid angle and b holds the cosine, so this is the rendering sum's own weighting), then "
    "the relative L2 of those sums: errors of opposite sign within one view cancel as in a "
    "rendered pixel.\n\n"
    "Average absolute error (`average_abs`), the largest absolute error (`max_abs`) and "
    "`zero_samples` are in table.csv and result.json.\n\n";

}  // namespace

std::vector<std::string> material_table_variants(const fs::path& file) {
  return declared_variants(file);
}

bool is_material_table(const fs::path& file) {
  return declared_kind(file) == "material_table";
}

void check_material_table(const fs::path& file, const std::string& variant) {
  (void)parse_table(file, variant);
}

fs::path material_table_folder(const fs::path& file, const std::string& variant,
                               const fs::path& out_root) {
  return out_root / (parse_table(file, variant).name + (variant.empty() ? "" : "-" + variant));
}

json run_material_table(const fs::path& file, const MaterialTableOptions& o) {
  TableSpec spec = parse_table(file, o.variant);
  if (!o.scene.empty()) spec.scene = o.scene;
  const fs::path folder = o.out_root / (spec.name + (o.variant.empty() ? "" : "-" + o.variant));
  if (fs::exists(folder / ".complete") && !o.force)
    throw ParameterError(
        fmt::format("{} holds a complete run (--force reruns it)", folder.string()));
  fs::remove(folder / ".complete");
  // Images of an earlier run (materials since renamed or removed) must not stay beside new ones.
  fs::remove_all(folder / "images");
  fs::create_directories(folder / "images");
  const Provenance prov = collect_provenance(o.command_line, o.device);
  StageCache cache;
  json rows = json::array();
  std::map<std::string, std::shared_ptr<const Btf>> btfs;
  for (const std::string& name : spec.btfs) {
    BtfParams bp;
    bp.resolution = spec.resolution;
    bp.view_side = spec.view_side;
    bp.light_side = spec.light_side;
    auto g = generate_btf_cached(name, bp, cache, CacheMode::kUse, o.show_progress);
    auto btf = std::make_shared<const Btf>(std::move(g.btf));
    btfs[name] = btf;
    std::vector<std::shared_ptr<const CompressedMaterial>> done;
    for (const MaterialConfig& m : spec.materials) {
      if (o.show_progress)
        std::fprintf(stderr, "[%s] %s: %s\n", spec.name.c_str(), name.c_str(), m.label.c_str());
      const auto t0 = std::chrono::steady_clock::now();
      auto material = compress_material(m.backend, m.params, btf);
      const double seconds = seconds_since(t0);
      const MaterialError err = material_error(*material, *btf);
      json row = {
          {"btf", name},
          {"resolution", btf->resolution()},
          {"view_side", btf->view_side()},
          {"light_side", btf->light_side()},
          {"samples_per_abrdf", btf->view_count() * btf->light_count()},
          {"btf_bytes", btf->bytes()},
          {"label", m.label},
          {"backend", m.backend},
          {"params", m.params},
          {"compress_seconds", seconds},
          {"stored_bytes", material->storage().total_bytes()},
          {"rel_l2", err.relative_l2},
          {"max_abs", err.max_abs},
          {"average_relative", finite_or_null(err.average_relative)},
          {"average_relative_worst_abrdf", finite_or_null(err.average_relative_worst_abrdf)},
          {"average_relative_floored", finite_or_null(err.average_relative_floored)},
          {"average_abs", err.average_abs},
          {"zero_samples", err.zero_samples},
          {"cosine_l2", finite_or_null(err.cosine_l2)},
          {"white_light_l2", finite_or_null(err.white_light_l2)},
          {"flops_per_pixel", material->flops_per_pixel()}};
      if (const auto* f = dynamic_cast<const FactoredMaterial*>(material.get())) {
        const json& tm = f->state().timings;
        const double fs_ = tm.value("factorization_seconds", 0.0);
        row["factorization_seconds"] = fs_;
        row["factorization_ms_per_abrdf"] = 1e3 * fs_ / btf->texel_count();
        row["clustering_seconds"] = tm.value("clustering_seconds", 0.0);
        row["factored_bytes"] = f->factored_bytes();
        row["clusters"] = {f->state().clusters_p, f->state().clusters_q, f->state().clusters_r};
      }
      rows.push_back(row);
      done.push_back(std::move(material));
    }
    write_tiles(*btf, done, tile_lights(btf->light_side(), spec.tile_polar_deg),
                folder / "images" / (name + "-tiles.png"));
  }

  // The scene with every part's BTF replaced by the image BTF, under each material.
  json images = json::array();
  {
    SceneDesc desc = parse_scene(resolve_scene(spec.scene));
    for (auto& part : desc.parts) part.btf = spec.image_btf;
    const std::vector<std::string> names = {"uncompressed"};
    PrepareOptions popt;
    popt.show_progress = o.show_progress;
    PreparedScene prepared = prepare_scene_for(desc, names, cache, popt);
    const auto& entry = CompressorRegistry::instance().get("uncompressed");
    CompressionResult ref = compress_cached("uncompressed", {}, prepared.input(entry),
                                            prepared.transfer.key, cache, CacheMode::kUse, false);
    const std::shared_ptr<const CompressedTransfer> transfer(std::move(ref.compressed));
    const Scene scene = build_scene(desc);
    CameraOverrides size;
    size.width = spec.width;
    size.height = spec.height;
    const Camera camera = scene_camera(scene, "", size);
    const Cubemap light =
        environment_cubemap(parse_environment(file, spec.environment), desc.cubemap_resolution);
    BtfParams bp;
    bp.resolution = spec.resolution;
    bp.view_side = spec.view_side;
    const auto render = [&](const std::string& backend,
                            const std::map<std::string, std::string>& p) {
      FrameRenderer r(scene.mesh, load_scene_materials(desc, bp, cache, backend, p), transfer,
                      o.device);
      r.set_camera(camera);
      r.set_environment(light);
      (void)r.render();
      return std::pair{r.image(), hit_mask(r.gbuffer())};
    };
    const auto [full, mask] = render("full", {});
    ToneMap tm;
    tm.auto_exposure = false;
    tm.exposure = exposure_of(full, mask);
    const RgbImage full_display = tone_mapped(full, tm);
    const std::string stem = spec.scene + "-" + spec.image_btf;
    write_png(full, folder / "images" / (stem + "-full.png"), tm);
    images.push_back({{"label", "full"}, {"file", "images/" + stem + "-full.png"}});
    for (const MaterialConfig& m : spec.materials) {
      const auto [img, unused] = render(m.backend, m.params);
      (void)unused;
      const std::string f = stem + "-" + m.label + ".png", e = stem + "-" + m.label + "-error.png";
      write_png(img, folder / "images" / f, tm);
      write_false_colour_png(error_false_colour(img, full, mask), folder / "images" / e);
      const RgbImage display = tone_mapped(img, tm);
      images.push_back({{"label", m.label},
                        {"file", "images/" + f},
                        {"error_map", "images/" + e},
                        {"image_error", to_json(image_error(img, full, mask))},
                        {"display_error", to_json(image_error(display, full_display, mask))},
                        {"ssim", ssim(display, full_display, mask)}});
    }
  }

  json result = {{"experiment",
                  {{"name", spec.name},
                   {"title", spec.title},
                   {"variant", o.variant},
                   {"file", file.string()},
                   {"resolution", spec.resolution},
                   {"view_side", spec.view_side},
                   {"light_side", spec.light_side},
                   {"scene", spec.scene},
                   {"image_btf", spec.image_btf},
                   {"environment", spec.environment},
                   {"paper", spec.paper},
                   {"paper_source", spec.paper_source}}},
                 {"provenance", to_json(prov)},
                 {"threads", tbb::info::default_concurrency()},
                 {"rows", rows},
                 {"images", images}};
  write_text_atomically(folder / "result.json", result.dump(2) + "\n");

  std::string csv =
      "btf,resolution,view_side,light_side,samples_per_abrdf,label,backend,params,"
      "factorization_ms_per_abrdf,clustering_seconds,compress_seconds,btf_mb,factored_mb,"
      "stored_mb,rel_l2,max_abs,average_relative,average_relative_worst_abrdf,"
      "average_relative_floored,average_abs,zero_samples,cosine_l2,white_light_l2,image_rel_l2,"
      "image_ssim,image_display_rmse\n";
  // The rendered image's measures, on the rows of the image BTF.
  std::map<std::string, const json*> image_of;
  for (const json& i : images) image_of[i.at("label").get<std::string>()] = &i;
  for (const json& r : rows) {
    std::string params;
    for (const auto& [k, v] : r.at("params").items())
      params += (params.empty() ? "" : " ") + k + "=" + v.get<std::string>();
    std::string image_cols = ",,";
    if (r.at("btf").get<std::string>() == spec.image_btf &&
        image_of.count(r.at("label").get<std::string>())) {
      const json& i = *image_of.at(r.at("label").get<std::string>());
      image_cols =
          fmt::format("{},{},{}", number(i.at("image_error"), "relative_l2", "{:.6g}"),
                      number(i, "ssim", "{:.6g}"), number(i.at("display_error"), "rmse", "{:.6g}"));
    }
    const auto g = [&](const char* key) {
      const std::string t = number(r, key, "{:.6g}");
      return t == "-" ? std::string() : t;
    };
    csv += fmt::format(
        "{},{},{},{},{},{},{},{},{},{},{:.3f},{},{},{},{:.6g},{:.6g},{},{},{},{},{},{},{},"
        "{}\n",
        r.at("btf").get<std::string>(), r.at("resolution").get<int>(), r.at("view_side").get<int>(),
        r.at("light_side").get<int>(), r.at("samples_per_abrdf").get<int>(),
        r.at("label").get<std::string>(), r.at("backend").get<std::string>(), params,
        g("factorization_ms_per_abrdf"), g("clustering_seconds"),
        r.at("compress_seconds").get<double>(), mb(r.at("btf_bytes").get<double>()),
        r.contains("factored_bytes") ? mb(r.at("factored_bytes").get<double>()) : std::string(),
        mb(r.at("stored_bytes").get<double>()), r.at("rel_l2").get<double>(),
        r.at("max_abs").get<double>(), g("average_relative"), g("average_relative_worst_abrdf"),
        g("average_relative_floored"), g("average_abs"), r.at("zero_samples").get<std::uint64_t>(),
        g("cosine_l2"), g("white_light_l2"), image_cols);
  }
  write_text_atomically(folder / "table.csv", "# " + prov.summary() + "\n" + csv);

  std::string md = fmt::format("# {}\n\nCommand: `{}`\n\nProvenance: {}\n\n", spec.title,
                               o.command_line, prov.summary());
  md += fmt::format(
      "BTFs of {0} x {0} texels (ABRDFs), {1} x {1} view and {2} x {2} light samples ({3} "
      "samples per ABRDF), generated by prtlab. Times are wall-clock on {4} threads; "
      "`factorisation ms / ABRDF` is the whole factorisation's time divided by the ABRDF count "
      "(single-thread times: `bench/material_factorization_bench`).\n\n",
      spec.resolution, spec.view_side, spec.light_side,
      spec.view_side * spec.view_side * spec.light_side * spec.light_side,
      tbb::info::default_concurrency());
  md += kErrorColumns;
  md +=
      "| BTF | material | compress s | factorisation ms / ABRDF | clustering s | BTF MB | "
      "factored MB | stored MB | rel. L2 | avg. rel. (Suykens) | worst ABRDF | avg. rel. "
      "floored | cos L2 | white-light L2 |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  // Factorisation time, clustering time and the factored size are a factored material's (P, Q,
  // R per texel); other materials have none, shown as "-".
  const auto factored_mb = [&](const json& r) {
    return r.contains("factored_bytes") ? mb(r.at("factored_bytes").get<double>())
                                        : std::string("-");
  };
  for (const json& r : rows)
    md += fmt::format(
        "| {} | {} | {:.2f} | {} | {} | {} | {} | {} | {:.4f} | {} | {} | {} | {} | {} |\n",
        r.at("btf").get<std::string>(), r.at("label").get<std::string>(),
        r.at("compress_seconds").get<double>(), number(r, "factorization_ms_per_abrdf", "{:.3f}"),
        number(r, "clustering_seconds", "{:.2f}"), mb(r.at("btf_bytes").get<double>()),
        factored_mb(r), mb(r.at("stored_bytes").get<double>()), r.at("rel_l2").get<double>(),
        number(r, "average_relative", "{:.4f}"),
        number(r, "average_relative_worst_abrdf", "{:.4f}"),
        number(r, "average_relative_floored", "{:.4f}"), number(r, "cosine_l2", "{:.4f}"),
        number(r, "white_light_l2", "{:.4f}"));
  if (!spec.paper.empty()) {
    md += fmt::format("\n## The paper's numbers\n\n{}\n\n| | |\n|---|---|\n", spec.paper_source);
    for (const auto& [k, v] : spec.paper) md += fmt::format("| {} | {} |\n", k, v);
  }
  if (!spec.notes.empty()) md += "\n## Reading the numbers\n\n" + spec.notes + "\n";
  md += "\n## Tiles (the paper's Fig. 3)\n\nTop view; rows are lights at polar angles ";
  md += fmt::format("{} degrees; columns: full, then ", fmt::join(spec.tile_polar_deg, ", "));
  for (std::size_t i = 0; i < spec.materials.size(); ++i)
    md += (i ? ", " : "") + spec.materials[i].label;
  md += ".\n\n";
  for (const std::string& name : spec.btfs)
    md += fmt::format("{}: ![{} tiles](images/{}-tiles.png)\n\n", name, name, name);
  md += fmt::format(
      "\n## {} with the {} BTF under {}\n\nAgainst the render with the full BTF, over the "
      "object's pixels: `image rel. L2` of the linear (HDR) images; `SSIM` (Wang et al. 2004, "
      "11 x 11 Gaussian window, sigma 1.5, `core/include/prtlab/image/ssim.h`) and `display "
      "RMSE` (in [0, 1] display units; 1/255 is one 8-bit level) of the tone-mapped images the "
      "PNGs show (the full render's exposure, gamma 2.2, clamped at 1).\n\n| material | image | "
      "error map | image rel. L2 | SSIM | display RMSE |\n|---|---|---|---|---|---|\n",
      spec.scene, spec.image_btf, spec.environment);
  for (const json& i : images)
    md += fmt::format(
        "| {} | ![]({}) | {} | {} | {} | {} |\n", i.at("label").get<std::string>(),
        i.at("file").get<std::string>(),
        i.contains("error_map") ? "![](" + i.at("error_map").get<std::string>() + ")" : "",
        i.contains("image_error") ? number(i.at("image_error"), "relative_l2", "{:.4f}")
                                  : std::string("reference"),
        i.contains("ssim") ? number(i, "ssim", "{:.4f}") : std::string(""),
        i.contains("display_error") ? number(i.at("display_error"), "rmse", "{:.4f}")
                                    : std::string(""));
  write_text_atomically(folder / "README.md", md);
  write_text_atomically(folder / ".complete", "");
  result["folder"] = folder.string();
  return result;
}

}  // namespace prt::experiments
