#include "experiment_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>

#include "plot_script.h"
#include "prtlab/base/build_info.h"
#include "prtlab/base/error.h"
#include "prtlab/storage/atomic_file.h"

namespace prt::experiments {
namespace {
namespace fs = std::filesystem;
using json = nlohmann::json;

// The largest L* error (relative L2, worst environment) a lossless backend shows from float
// rounding alone sits orders of magnitude below this; below it the report treats backends as
// exact.
constexpr double kExactError = 1e-6;

double num(const json& v) {
  return v.is_number() ? v.get<double>() : NAN;
}

std::string fmt_num(const json& v, const char* spec = "{:.3g}") {
  if (!v.is_number()) return "n/a";
  return fmt::format(fmt::runtime(spec), v.get<double>());
}

std::string fmt_ms(const json& v) {
  return v.is_number() ? fmt::format("{:.3f}", v.get<double>()) : "n/a";
}

std::string fmt_err(const json& v) {
  if (!v.is_number()) return "n/a";
  const double x = v.get<double>();
  return x == 0 ? "0" : fmt::format("{:.3g}", x);
}

std::string params_cell(const json& p) {
  std::string s = p.is_string() ? p.get<std::string>() : "";
  // seed is every backend's and rarely interesting; keep the table narrow.
  std::string out;
  std::size_t start = 0;
  while (start <= s.size()) {
    const std::size_t end = std::min(s.find(';', start), s.size());
    const std::string kv = s.substr(start, end - start);
    if (!kv.empty() && !kv.starts_with("seed=")) out += (out.empty() ? "" : ", ") + kv;
    start = end + 1;
  }
  return out.empty() ? "defaults" : "`" + out + "`";
}

// A point's value of `key`: a points.csv column, or "metrics.<name>", the backend metric <name>
// (CompressedTransfer::backend_metrics()); null where the point has none.
json point_value(const json& p, const std::string& key) {
  constexpr std::string_view kMetric = "metrics.";
  if (key.starts_with(kMetric)) {
    const json m = p.value("backend_metrics", json(nullptr));
    const std::string name = key.substr(kMetric.size());
    return m.is_object() && m.contains(name) ? m.at(name) : json(nullptr);
  }
  return p.value(key, json(nullptr));
}

std::vector<const json*> points_of(const json& result, const std::string& scene) {
  std::vector<const json*> out;
  for (const auto& p : result.at("points"))
    if (p.at("scene") == scene) out.push_back(&p);
  return out;
}

std::string paper_cell(const json& result, const std::string& backend) {
  const json& paper = result.at("paper");
  return paper.contains(backend) ? paper.at(backend).get<std::string>() : "";
}

std::optional<json> load_json(const fs::path& file) {
  std::ifstream in(file);
  if (!in) return std::nullopt;
  try {
    return json::parse(in);
  } catch (const json::exception&) {
    return std::nullopt;
  }
}

// SSIM per (scene, backend, environment, view) from perceptual.json, when the plot script
// wrote one.
std::map<std::string, double> ssim_table(const fs::path& folder) {
  std::map<std::string, double> out;
  const auto j = load_json(folder / "perceptual.json");
  if (!j || !j->contains("ssim")) return out;
  for (const auto& e : j->at("ssim"))
    out[e.at("image").get<std::string>()] = e.at("ssim").get<double>();
  return out;
}

void equal_storage_section(std::string& md, const json& result, const json& scene,
                           const fs::path& folder) {
  const std::string name = scene.at("scene");
  const double target = num(scene.at("target_bytes"));
  const double tol = result.at("experiment").at("target").at("tolerance").get<double>();
  md += fmt::format("## {} at equal storage\n\n", name);
  md += fmt::format(
      "Target: {:.3f} MB ({}), each backend's size knob searched to within {:g} %. Scene: {} "
      "vertices, M = {}, N = {}, nnz(T) = {}.\n\n",
      target / 1e6,
      scene.at("target_backend").is_string()
          ? "the storage of `" + scene.at("target_backend").get<std::string>() + "` on this scene"
          : std::string("fixed by the experiment file"),
      100 * tol, scene.at("vertices").get<std::size_t>(), scene.at("M").get<int>(),
      scene.at("N").get<int>(), scene.at("nnz").get<std::uint64_t>());
  const auto ssim = ssim_table(folder);
  md +=
      "| backend | parameters | storage MB | / target | reached | compress s | MFLOPs | "
      "relight ms C++ | relight ms OpenCL | L* rel. L2 mean | L* rel. L2 max | Frobenius rel. | "
      "Frobenius SE | image rel. L2 | PSNR dB |";
  if (!ssim.empty()) md += " SSIM |";
  md += " paper |\n|---|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|";
  if (!ssim.empty()) md += "---:|";
  md += "---|\n";
  for (const json* p : points_of(result, name)) {
    const std::string backend = p->at("backend");
    std::string ssim_cell;
    if (!ssim.empty() && p->contains("images") && !p->at("images").empty()) {
      double sum = 0;
      int n = 0;
      for (const auto& im : p->at("images"))
        if (auto it = ssim.find(im.at("image").get<std::string>()); it != ssim.end())
          sum += it->second, ++n;
      ssim_cell = n ? fmt::format("{:.4f}", sum / n) : "n/a";
    }
    md += fmt::format(
        "| `{}` | {} | {:.3f} | {:.3f} | {} | {} | {:.2f} | {} | {} | {} | {} | {} | {} | {} | {} "
        "|",
        backend, params_cell(p->at("params")), num(p->at("storage_bytes")) / 1e6,
        num(p->at("storage_ratio")), p->at("reached").get<bool>() ? "yes" : "**no**",
        fmt_num(p->at("compress_seconds"), "{:.2f}"), num(p->at("flops_per_relight")) / 1e6,
        fmt_ms(p->at("relight_ms_cpp")), fmt_ms(p->at("relight_ms_opencl")),
        fmt_err(p->at("lstar_rel_l2_mean")), fmt_err(p->at("lstar_rel_l2_max")),
        fmt_err(p->at("frobenius_rel")), fmt_err(p->value("frobenius_se", json(nullptr))),
        fmt_err(p->at("image_rel_l2_mean")), fmt_num(p->at("image_psnr_db_mean"), "{:.1f}"));
    if (!ssim.empty()) md.append(" ").append(ssim_cell).append(" |");
    md.append(" ").append(paper_cell(result, backend)).append(" |\n");
  }
  md += "\n";

  // The winner among every backend at the target or below it (less storage is no handicap).
  std::vector<const json*> reached;
  for (const json* p : points_of(result, name))
    if (num(p->at("storage_ratio")) <= 1.0 + tol && p->at("lstar_rel_l2_mean").is_number())
      reached.push_back(p);
  std::sort(reached.begin(), reached.end(), [](const json* a, const json* b) {
    return num(a->at("lstar_rel_l2_mean")) < num(b->at("lstar_rel_l2_mean"));
  });
  // Errors at float rounding are ties: two exact backends differ only in relight time.
  const auto exact = [](const json* p) { return num(p->at("lstar_rel_l2_max")) < kExactError; };
  const auto speed = [](const json* p) {
    return p->at("relight_ms_opencl").is_number() ? num(p->at("relight_ms_opencl"))
                                                  : num(p->at("relight_ms_cpp"));
  };
  std::vector<const json*> exact_ones;
  for (const json* p : reached)
    if (exact(p)) exact_ones.push_back(p);
  if (reached.empty()) {
    md += "No backend reached the target storage or went below it.\n\n";
  } else if (exact_ones.size() >= 2) {
    // By relight time; untimed runs (NaN) keep their order.
    std::stable_sort(exact_ones.begin(), exact_ones.end(),
                     [&](const json* a, const json* b) { return speed(a) < speed(b); });
    std::string names;
    for (const json* p : exact_ones)
      names += (names.empty() ? "`" : ", `") + p->at("backend").get<std::string>() + "`";
    md += fmt::format(
        "**Exact at the target storage or below: {}** (L* error at float rounding, below {:.0e})",
        names, kExactError);
    if (std::isfinite(speed(exact_ones[0])) && std::isfinite(speed(exact_ones[1])))
      md += fmt::format(
          "; the fastest relight among them is `{}` ({:.3f} ms against {:.3f} ms for "
          "`{}`, {:.2f}x)",
          exact_ones[0]->at("backend").get<std::string>(), speed(exact_ones[0]),
          speed(exact_ones[1]), exact_ones[1]->at("backend").get<std::string>(),
          speed(exact_ones[1]) / speed(exact_ones[0]));
    md += ".";
    const json* lossy = nullptr;
    for (const json* p : reached)
      if (!exact(p)) {
        lossy = p;
        break;
      }
    if (lossy)
      md += fmt::format(" The best lossy backend, `{}`, has a mean L* error of {}.",
                        lossy->at("backend").get<std::string>(),
                        fmt_err(lossy->at("lstar_rel_l2_mean")));
    md += "\n\n";
  } else if (reached.size() == 1) {
    md += fmt::format("Only `{}` reached the target storage or went below it.\n\n",
                      reached[0]->at("backend").get<std::string>());
  } else {
    const double e0 = num(reached[0]->at("lstar_rel_l2_mean"));
    const double e1 = num(reached[1]->at("lstar_rel_l2_mean"));
    // A factor against an error at float rounding means nothing: say exact instead.
    md += fmt::format(
        "**Lowest error at equal storage: `{}`** (mean relative L2 of L* {}{}), {} the runner-up "
        "`{}` ({}).\n\n",
        reached[0]->at("backend").get<std::string>(), fmt_err(reached[0]->at("lstar_rel_l2_mean")),
        exact(reached[0]) ? ", exact to float rounding" : "",
        exact(reached[0]) ? std::string("against") : fmt::format("{:.3g}x lower than", e1 / e0),
        reached[1]->at("backend").get<std::string>(), fmt_err(reached[1]->at("lstar_rel_l2_mean")));
  }
  std::string unreached;
  for (const auto& s : result.at("searches"))
    if (s.at("scene") == name && s.at("reached") != true)
      unreached += fmt::format("- `{}`: {}\n", s.at("backend").get<std::string>(),
                               s.value("note", std::string()).empty()
                                   ? fmt::format("storage {:.3f} x the target", num(s.at("ratio")))
                                   : s.at("note").get<std::string>());
  if (!unreached.empty()) md += "Backends that did not reach the target:\n\n" + unreached + "\n";
  md += "Searches (compressions spent, knob value found):\n\n";
  for (const auto& s : result.at("searches"))
    if (s.at("scene") == name && s.contains("probes"))
      md += fmt::format("- `{}`: {} = {} after {} compressions ({:.3f} MB)\n",
                        s.at("backend").get<std::string>(), s.at("knob").get<std::string>(),
                        s.at("value").get<std::string>(), s.at("probes").size(),
                        num(s.at("bytes")) / 1e6);
  md += "\n";
  const std::string fig = fmt::format("figure-{}.png", name);
  if (fs::exists(folder / fig))
    md += fmt::format(
        "![images and error maps at equal storage]({})\n\nImages at the exact "
        "image's exposure; error maps: per-pixel relative error, one colour scale "
        "for all backends (viridis, 0 to the largest 99th percentile).\n\n",
        fig);
}

void sweep_section(std::string& md, const json& result, const json& scene, const fs::path& folder) {
  const std::string name = scene.at("scene");
  md += fmt::format("## {}\n\n", name);
  md += fmt::format(
      "{} vertices, M = {}, N = {}, nnz(T) = {}; T {} ({:.1f} s when computed).\n\n",
      scene.at("vertices").get<std::size_t>(), scene.at("M").get<int>(), scene.at("N").get<int>(),
      scene.at("nnz").get<std::uint64_t>(),
      scene.at("transfer_cache_hit").get<bool>() ? "from the stage cache" : "computed in this run",
      num(scene.at("transfer_seconds")));
  const bool fps = result.at("experiment").at("fps").get<bool>();
  md +=
      "| backend | parameters | storage MB | computation % | compress s | relight ms C++ | "
      "relight ms OpenCL | L* rel. L2 mean | L* rel. L2 max | image rel. L2 | PSNR dB |";
  if (fps) md += " fps view | fps light |";
  md += " front (time / storage) |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|";
  if (fps) md += "---:|---:|";
  md += "---|\n";
  for (const json* p : points_of(result, name)) {
    md += fmt::format("| `{}` | {} | {:.3f} | {:.2f} | {} | {} | {} | {} | {} | {} | {} |",
                      p->at("backend").get<std::string>(), params_cell(p->at("params")),
                      num(p->at("storage_bytes")) / 1e6, num(p->at("computation_percent")),
                      fmt_num(p->at("compress_seconds"), "{:.2f}"), fmt_ms(p->at("relight_ms_cpp")),
                      fmt_ms(p->at("relight_ms_opencl")), fmt_err(p->at("lstar_rel_l2_mean")),
                      fmt_err(p->at("lstar_rel_l2_max")), fmt_err(p->at("image_rel_l2_mean")),
                      fmt_num(p->at("image_psnr_db_mean"), "{:.1f}"));
    if (fps)
      md += fmt::format(" {} | {} |", fmt_num(p->at("fps_view"), "{:.1f}"),
                        fmt_num(p->at("fps_light"), "{:.1f}"));
    md += fmt::format(" {} / {} |\n", p->at("pareto_time") == true ? "yes" : "",
                      p->at("pareto_storage") == true ? "yes" : "");
  }
  md += "\n";
  if (fps) {
    // What culling and dark faces save: the relight stage of light-change frames.
    std::vector<std::string> envs;
    for (const auto& env : result.at("experiment").at("environments"))
      envs.push_back(env.at("name").get<std::string>());
    md +=
        "Skipping what a frame does not need (relight stage of light-change frames, median; "
        "culled: only the vertices of the view's hit triangles; identical: the culled frame "
        "equals the full one bit for bit):\n\n";
    md +=
        "| backend | parameters | culls | visible vertices | relight ms culled | relight ms "
        "full | speedup | identical |";
    for (const auto& e : envs) md.append(" relight ms, ").append(e).append(" |");
    md += "\n|---|---|---|---:|---:|---:|---:|---|";
    for (std::size_t i = 0; i < envs.size(); ++i) md += "---:|";
    md += "\n";
    for (const json* p : points_of(result, name)) {
      md += fmt::format(
          "| `{}` | {} | {} | {} of {} | {} | {} | {} | {} |", p->at("backend").get<std::string>(),
          params_cell(p->at("params")),
          p->value("culls", json(nullptr)).is_boolean()
              ? (p->at("culls").get<bool>() ? "yes" : "no")
              : "n/a",
          p->value("visible_vertices", json(nullptr)).is_number() ? p->at("visible_vertices").dump()
                                                                  : std::string("n/a"),
          p->at("vertices").dump(), fmt_ms(p->value("relight_ms_frame_culled", json(nullptr))),
          fmt_ms(p->value("relight_ms_frame_unculled", json(nullptr))),
          fmt_num(p->value("cull_speedup", json(nullptr)), "{:.2f}x"),
          p->value("cull_identical", json(nullptr)).is_boolean()
              ? (p->at("cull_identical").get<bool>() ? "yes" : "**NO**")
              : "n/a");
      for (const auto& e : envs) {
        json ms = nullptr;
        for (const auto& er : p->at("errors"))
          if (er.at("environment") == e) ms = er.value("relight_ms_frame", json(nullptr));
        md.append(" ").append(fmt_ms(ms)).append(" |");
      }
      md += "\n";
    }
    md += "\n";
  }
  const std::string plot = fmt::format("pareto-{}.png", name);
  if (fs::exists(folder / plot))
    md += fmt::format("![error against relight time and storage]({})\n\n", plot);
}

// A sweep over scene variants (the paper's Fig. 8): one row per variant and backend.
void scaling_section(std::string& md, const json& result, const fs::path& folder) {
  const json& grid = result.at("experiment").at("scene_grid");
  if (grid.empty()) return;
  md += "## Scaling over scene variants\n\n";
  std::string keys;
  for (const auto& [k, _] : grid.items()) keys += (keys.empty() ? "" : ", ") + k;
  md += fmt::format(
      "Swept: {}. Storage relative to the first variant of the same base scene "
      "and backend.\n\n",
      keys);
  md +=
      "| scene | backend | storage MB | x first | computation % | compress s | fps view | "
      "fps light |\n|---|---|---:|---:|---:|---:|---:|---:|\n";
  std::map<std::pair<std::string, std::string>, double> first;
  std::map<std::string, std::string> base_of;
  for (const auto& s : result.at("scenes")) base_of[s.at("scene")] = s.at("base");
  for (const auto& p : result.at("points")) {
    const auto key = std::pair{base_of[p.at("scene")], p.at("backend").get<std::string>()};
    const double mb = num(p.at("storage_bytes")) / 1e6;
    if (!first.contains(key)) first[key] = mb;
    md += fmt::format("| {} | `{}` | {:.3f} | {:.2f} | {:.2f} | {} | {} | {} |\n",
                      p.at("scene").get<std::string>(), p.at("backend").get<std::string>(), mb,
                      mb / first[key], num(p.at("computation_percent")),
                      fmt_num(p.at("compress_seconds"), "{:.2f}"),
                      fmt_num(p.at("fps_view"), "{:.1f}"), fmt_num(p.at("fps_light"), "{:.1f}"));
  }
  md += "\n";
  if (fs::exists(folder / "scaling.png"))
    md += "![storage and frame rate against the swept setting](scaling.png)\n\n";
}

// What the backends measured of themselves (CompressedTransfer::backend_metrics()): per scene
// and backend that declares any, a row per point with every metric, and what each one means.
void backend_metrics_section(std::string& md, const json& result) {
  std::string body;
  for (const auto& scene : result.at("scenes")) {
    const std::string name = scene.at("scene");
    std::map<std::string, std::vector<const json*>> by_backend;
    std::map<std::string, std::map<std::string, std::string>> meanings;
    for (const json* p : points_of(result, name)) {
      const json m = p->value("backend_metrics", json(nullptr));
      if (!m.is_object() || m.empty()) continue;
      const std::string backend = p->at("backend");
      by_backend[backend].push_back(p);
      const json mean = p->value("backend_metric_meanings", json::object());
      for (const auto& [k, _] : m.items())
        meanings[backend][k] = mean.is_object() ? mean.value(k, std::string()) : std::string();
    }
    for (const auto& [backend, points] : by_backend) {
      body += fmt::format("{}, `{}`:\n\n| parameters |", name, backend);
      std::string rule = "|---|";
      for (const auto& [k, _] : meanings[backend]) {
        body += fmt::format(" {} |", k);
        rule += "---:|";
      }
      body += "\n" + rule + "\n";
      for (const json* p : points) {
        body += fmt::format("| {} |", params_cell(p->at("params")));
        for (const auto& [k, _] : meanings[backend])
          body += fmt::format(" {} |", fmt_num(point_value(*p, "metrics." + k), "{:.5g}"));
        body += "\n";
      }
      body += "\n";
      for (const auto& [k, meaning] : meanings[backend])
        body += fmt::format("- `{}`: {}\n", k, meaning.empty() ? "(no description)" : meaning);
      body += "\n";
    }
  }
  if (body.empty()) return;
  md +=
      "## Backend metrics\n\nWhat each backend measured of itself while compressing "
      "(`backend_metrics` in result.json and points.csv; curves name them `metrics.<name>`).\n\n";
  md += body;
}

// The experiment's [[curves]] (docs/experiments.md "Curves"): per curve and scene a table of
// the curve's points and the plot scripts/plot_experiment.py drew.
void curves_section(std::string& md, const json& result, const fs::path& folder) {
  const json curves = result.at("experiment").value("curves", json::array());
  if (curves.empty()) return;
  md += "## Curves\n\n";
  for (std::size_t n = 0; n < curves.size(); ++n) {
    const json& c = curves[n];
    const std::string backend = c.at("backend"), x = c.at("x"), y = c.at("y");
    const std::string series = c.at("series"), panel = c.at("panel");
    const std::string title = c.value("title", std::string());
    md += fmt::format("### {}\n\n",
                      title.empty() ? fmt::format("`{}`: {} against {}", backend, y, x) : title);
    for (const auto& scene : result.at("scenes")) {
      const std::string name = scene.at("scene");
      std::string rows;
      for (const auto& p : result.at("points")) {
        if (p.at("scene") != name || p.at("backend") != backend) continue;
        const json& cp = p.at("canonical_params");
        // A parameter, or (for x) a points.csv column such as storage_mb.
        const auto par = [&](const std::string& k) {
          if (k.empty()) return std::string("-");
          if (cp.contains(k)) return cp.value(k, std::string("?"));
          const json v = point_value(p, k);
          return v.is_null() ? std::string("?") : fmt_num(v, "{:.4g}");
        };
        rows +=
            fmt::format("| {} | {} | {} | {} | {:.3f} | {} |\n", par(panel), par(series), par(x),
                        fmt_num(point_value(p, y), "{:.4g}"), num(p.at("storage_bytes")) / 1e6,
                        fmt_num(p.value("compress_seconds", json(nullptr)), "{:.2f}"));
      }
      if (rows.empty()) continue;
      md += fmt::format(
          "{}:\n\n| {} | {} | {} | {} | storage MB | compress s |\n"
          "|---|---|---:|---:|---:|---:|\n{}\n",
          name, panel.empty() ? "-" : panel, series.empty() ? "-" : series, x, y, rows);
      const std::string plot = fmt::format("curves{}-{}.png", n, name);
      if (fs::exists(folder / plot)) md += fmt::format("![{} against {}]({})\n\n", y, x, plot);
    }
  }
}

}  // namespace

std::string render_experiment_markdown(const json& result, const fs::path& folder) {
  const json& e = result.at("experiment");
  const json& prov = result.at("provenance");
  std::string md;
  md += fmt::format("# {}\n\n", e.at("title").get<std::string>());
  md += fmt::format(
      "Experiment `{}`{} ({}), from `{}`. Written by `prtlab experiment run`; redraw with "
      "`prtlab experiment report {}` (docs/experiments.md).\n\n",
      e.at("name").get<std::string>(),
      e.at("variant").get<std::string>().empty()
          ? ""
          : fmt::format(", variant `{}`", e.at("variant").get<std::string>()),
      e.at("kind").get<std::string>(), e.at("file").get<std::string>(), folder.string());
  md += "| | |\n|---|---|\n";
  md += fmt::format("| command | `{}` |\n", prov.value("command", std::string()));
  md += fmt::format("| provenance | {} |\n", prov.value("summary", std::string()));
  md += fmt::format(
      "| load average at start | {} (/proc/loadavg: 1, 5, 15 min; timings on a "
      "loaded machine are inflated) |\n",
      prov.value("load_average_at_start", std::string("unknown")));
  std::string envs;
  for (const auto& env : e.at("environments"))
    envs += (envs.empty() ? "" : ", ") + env.at("name").get<std::string>();
  md += fmt::format("| environments | {} (the L* error is the mean / max over them) |\n", envs);
  md += fmt::format(
      "| images | {} x {}, views: {} |\n", e.at("width").get<int>(), e.at("height").get<int>(),
      e.at("views").empty() ? std::string("the scene's first") : e.at("views").dump());
  md += fmt::format("| timing | {} |\n",
                    e.at("timing").get<bool>()
                        ? fmt::format("median of {} relights; OpenCL: kernel time from events",
                                      e.at("repeats").get<int>())
                        : std::string("off (deterministic run)"));
  const json& c = result.at("cache");
  md += fmt::format(
      "| stage cache | {} points from the cache ({:.1f} s of measuring saved), {} computed "
      "({:.1f} s); {} stage hits, {} misses |\n\n",
      c.at("points_from_cache").get<int>(), num(c.at("seconds_saved")),
      c.at("points_computed").get<int>(), num(c.at("seconds_computing")),
      c.at("stage_hits").get<int>(), c.at("stage_misses").get<int>());

  if (result.contains("failures") && !result.at("failures").empty()) {
    md +=
        "## Failures\n\nThese points did not run (nothing of them is cached; the rest of the "
        "experiment did):\n\n";
    for (const auto& f : result.at("failures"))
      md += fmt::format("- {} {}: {}\n", f.at("scene").get<std::string>(),
                        f.at("point").get<std::string>().empty()
                            ? std::string("(the scene)")
                            : fmt::format("`{}`", f.at("point").get<std::string>()),
                        f.at("error").get<std::string>());
    md += "\n";
  }
  for (const auto& scene : result.at("scenes")) {
    if (e.at("kind") == "equal_storage")
      equal_storage_section(md, result, scene, folder);
    else
      sweep_section(md, result, scene, folder);
  }
  scaling_section(md, result, folder);
  backend_metrics_section(md, result);
  curves_section(md, result, folder);

  if (!result.at("paper").empty()) {
    md += "## The papers' numbers\n\n";
    if (!result.at("paper_source").get<std::string>().empty())
      md += result.at("paper_source").get<std::string>() + "\n\n";
    md += "| backend | paper |\n|---|---|\n";
    for (const auto& [k, v] : result.at("paper").items())
      md += fmt::format("| `{}` | {} |\n", k, v.get<std::string>());
    md += "\n";
  }
  md +=
      "## Files\n\n"
      "- `result.json`: everything above and more (spec, provenance, searches, per-environment "
      "errors, storage components)\n"
      "- `points.csv`: one row per point, fixed columns (docs/experiments.md)\n"
      "- `errors.csv`: one row per point, environment and view\n";
  if (fs::exists(folder / "images")) md += "- `images/`: the kept images and error maps\n";
  if (fs::exists(folder / "perceptual.json"))
    md += "- `perceptual.json`: SSIM (scikit-image) of each image against the exact one\n";
  return md;
}

void write_experiment_report(const fs::path& folder, bool plots, bool quiet) {
  const auto result = load_json(folder / "result.json");
  if (!result)
    throw InputError(folder / "result.json",
                     "missing or not valid JSON (run the experiment first)");
  // perceptual.json belongs to the plots of this result: never let an older one survive.
  std::error_code ec;
  fs::remove(folder / "perceptual.json", ec);
  if (plots) run_plot_script("plot_experiment.py", shell_quote(folder.string()), quiet);
  try {
    write_text_atomically(folder / "README.md", render_experiment_markdown(*result, folder));
  } catch (const json::exception& e) {
    throw InputError(folder / "result.json", fmt::format("not a prtlab result: {}", e.what()));
  }
}

}  // namespace prt::experiments
