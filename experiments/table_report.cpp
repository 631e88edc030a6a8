#include "table_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "prtlab/storage/atomic_file.h"

namespace prt::experiments {
namespace {

const std::string kNa = "n/a";

std::string num(double v) {
  return fmt::format("{}", v);
}
std::string num(std::optional<double> v) {
  return v ? num(*v) : kNa;
}

template <typename F>
std::string paper(const SceneRow& r, F field) {
  return r.paper ? num(field(*r.paper)) : kNa;
}

struct CsvColumn {
  std::string name;
  std::function<std::string(const SceneRow&)> value;
};

const std::vector<CsvColumn>& columns() {
  static const std::vector<CsvColumn> kColumns = {
      {"scene", [](const SceneRow& r) { return r.scene; }},
      {"backend", [](const SceneRow& r) { return r.backend; }},
      {"reference", [](const SceneRow& r) { return r.reference; }},
      {"vertices", [](const SceneRow& r) { return std::to_string(r.vertices); }},
      {"paper_vertices",
       [](const SceneRow& r) { return paper(r, [](auto& p) { return p.vertices; }); }},
      {"local_directions", [](const SceneRow& r) { return std::to_string(r.local_count); }},
      {"global_directions", [](const SceneRow& r) { return std::to_string(r.pixel_count); }},
      {"supersampling", [](const SceneRow& r) { return std::to_string(r.supersampling); }},
      {"nnz", [](const SceneRow& r) { return std::to_string(r.nnz); }},
      {"nnz_millions", [](const SceneRow& r) { return num(r.nnz_millions); }},
      {"paper_nnz_millions",
       [](const SceneRow& r) { return paper(r, [](auto& p) { return p.nnz_millions; }); }},
      {"mflops", [](const SceneRow& r) { return num(r.mflops); }},
      {"paper_mflops",
       [](const SceneRow& r) { return paper(r, [](auto& p) { return p.mflops; }); }},
      {"reduced_mflops", [](const SceneRow& r) { return num(r.reduced_mflops); }},
      {"paper_reduced_mflops",
       [](const SceneRow& r) { return paper(r, [](auto& p) { return p.reduced_mflops; }); }},
      {"computation_percent", [](const SceneRow& r) { return num(r.computation_percent); }},
      {"paper_computation_percent",
       [](const SceneRow& r) { return paper(r, [](auto& p) { return p.computation_percent; }); }},
      {"dense_mb", [](const SceneRow& r) { return num(r.dense_mb); }},
      {"paper_dense_mb",
       [](const SceneRow& r) { return paper(r, [](auto& p) { return p.data_mb; }); }},
      {"reduced_mb", [](const SceneRow& r) { return num(r.reduced_mb); }},
      {"paper_reduced_mb",
       [](const SceneRow& r) { return paper(r, [](auto& p) { return p.reduced_mb; }); }},
      {"data_percent", [](const SceneRow& r) { return num(r.data_percent); }},
      {"paper_data_percent",
       [](const SceneRow& r) { return paper(r, [](auto& p) { return p.data_percent; }); }},
      {"precompute_minutes", [](const SceneRow& r) { return num(r.precompute_minutes); }},
      {"paper_precompute_minutes",
       [](const SceneRow& r) { return paper(r, [](auto& p) { return p.precompute_minutes; }); }},
      {"transfer_minutes", [](const SceneRow& r) { return num(r.transfer_seconds / 60.0); }},
      {"compress_minutes", [](const SceneRow& r) { return num(r.compress_seconds / 60.0); }},
      {"backend_ms_cpp", [](const SceneRow& r) { return num(r.subject.ms_cpp); }},
      {"backend_ms_opencl", [](const SceneRow& r) { return num(r.subject.ms_opencl); }},
      {"reference_ms_cpp", [](const SceneRow& r) { return num(r.reference_timing.ms_cpp); }},
      {"reference_ms_opencl", [](const SceneRow& r) { return num(r.reference_timing.ms_opencl); }},
      {"frobenius_rel_error", [](const SceneRow& r) { return num(r.frobenius_rel_error); }},
      {"frobenius_rel_error_stderr",
       [](const SceneRow& r) { return num(r.frobenius_rel_error_stderr); }},
      {"max_vertex_rel_error", [](const SceneRow& r) { return num(r.max_vertex_rel_error); }},
      {"rel_l2_error_max", [](const SceneRow& r) { return num(r.rel_l2_error_max); }},
      {"lossless",
       [](const SceneRow& r) { return std::string(r.lossless.exact() ? "exact" : "not-exact"); }},
      {"lossless_probe_mismatches",
       [](const SceneRow& r) { return std::to_string(r.lossless.cpp.mismatches); }},
      {"lossless_max_count_error",
       [](const SceneRow& r) { return num(r.lossless.cpp.max_count_error); }},
      {"lossless_random_max_rel_error",
       [](const SceneRow& r) { return num(r.lossless.cpp.random_max_rel_error); }},
      {"lossless_opencl_probe_mismatches",
       [](const SceneRow& r) {
         return r.lossless.opencl ? std::to_string(r.lossless.opencl->mismatches) : std::string();
       }},
      {"lossless_opencl_random_max_rel_error",
       [](const SceneRow& r) {
         return r.lossless.opencl ? num(r.lossless.opencl->random_max_rel_error) : std::string();
       }},
  };
  return kColumns;
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string thousands(double v) {
  const auto digits = fmt::format("{:.0f}", std::abs(v));
  std::string out = v < 0 && digits != "0" ? "-" : "";
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out.push_back(',');
    out.push_back(digits[i]);
  }
  return out;
}

std::string fixed(double v, int decimals) {
  return fmt::format("{:.{}f}", v, decimals);
}
std::string fixed(std::optional<double> v, int decimals) {
  return v ? fixed(*v, decimals) : kNa;
}

std::string device_label(const TableResult& r) {
  const auto& d = r.provenance.opencl_device;
  return d.is_object() && d.contains("label") ? d["label"].get<std::string>() : "none";
}

std::string reproduce_command(const TableResult& r) {
  std::string scenes;
  for (const auto& row : r.rows) {
    if (!scenes.empty()) scenes += ',';
    scenes += row.scene;
  }
  std::string params;
  for (const auto& [k, v] : r.parameters["backend_parameters"].items())
    params += fmt::format(" --param {}={}", k, v.get<std::string>());
  return fmt::format("prtlab experiment {} --scenes {}{} --repeats {}", to_string(r.table), scenes,
                     params, r.parameters["repeats"].get<int>());
}

}  // namespace

std::vector<std::string> csv_columns() {
  std::vector<std::string> out;
  for (const auto& c : columns()) out.push_back(c.name);
  return out;
}

std::vector<std::string> table_notes(const TableResult& result) {
  std::vector<std::string> notes;
  for (const auto& r : result.rows) {
    if (!r.paper) {
      notes.push_back(fmt::format("{}: not a scene of the paper's {}; its paper columns are n/a.",
                                  r.scene, short_name(result.table)));
      continue;
    }
    const auto& p = *r.paper;
    const double ours_per_vertex = static_cast<double>(r.nnz) / static_cast<double>(r.vertices);
    const double paper_per_vertex = p.nnz_millions * 1e6 / p.vertices;
    notes.push_back(fmt::format(
        "{}: nnz(T) {:.2f} M is {:.0f} % of the paper's {:.1f} M ({:.0f} vs {:.0f} entries per "
        "vertex; a hemisphere holds N/2 = {} pixels). Our T clips at the tangent plane: a pixel "
        "with no unblocked sub-ray above it has no entry. {} Our mesh is a stand-in for the "
        "paper's model (docs/scenes.md){}.",
        r.scene, r.nnz_millions, 100.0 * r.nnz_millions / p.nnz_millions, p.nnz_millions,
        ours_per_vertex, paper_per_vertex, r.pixel_count / 2,
        paper_per_vertex > r.pixel_count / 2
            ? "The paper's count per vertex exceeds a hemisphere, so it keeps some below-horizon "
              "directions (docs/transfer.md, \"nnz vs the paper\")."
        : ours_per_vertex > paper_per_vertex
            ? "The paper's model is less open to the sky than ours (the count per vertex "
              "is the visible fraction of the hemisphere: different geometry, different "
              "self-occlusion)."
            : "Our model is less open to the sky than the paper's (the count per vertex "
              "is the visible fraction of the hemisphere: different geometry, different "
              "self-occlusion).",
        static_cast<double>(r.vertices) != p.vertices
            ? fmt::format(" with {} vertices vs the paper's {}", thousands(r.vertices),
                          thousands(p.vertices))
            : ""));
    const double paper_product = p.vertices * r.local_count * r.pixel_count / 1e6;
    if (std::abs(paper_product - p.data_mb) > 0.03 * p.data_mb)
      notes.push_back(fmt::format(
          "{}: dense data size is vertices x M x N bytes / 1e6 = {} MB here; the paper prints "
          "{} MB although its own {} x {} x {} gives {} MB.",
          r.scene, thousands(r.dense_mb), thousands(p.data_mb), thousands(p.vertices),
          r.local_count, r.pixel_count, thousands(paper_product)));
    const auto largest = std::max_element(
        r.storage.begin(), r.storage.end(),
        [](const StorageComponent& a, const StorageComponent& b) { return a.bytes < b.bytes; });
    notes.push_back(fmt::format(
        "{}: computation {:.1f} % vs the paper's {:.1f} %, data {:.2f} % vs {:.2f} %. FLOPs are "
        "counted as the paper counts them (a bicluster costs r + 2l - 1, a residual term 2; "
        "compressors/bicluster/README.md); storage is our layout{}, the paper does not give its "
        "layout. Both percentages are relative to our own T, which has {} entries than the "
        "paper's.",
        r.scene, r.computation_percent, p.computation_percent, r.data_percent, p.data_percent,
        largest != r.storage.end() ? fmt::format(" ({} {:.1f} of {:.1f} MB)", largest->name,
                                                 largest->bytes / 1e6, r.reduced_mb)
                                   : "",
        r.nnz_millions < p.nnz_millions ? "fewer" : "more"));
  }
  notes.push_back(
      "Precomputation: T's computation (Embree visibility and binning, without building the "
      "mesh) plus the biclustering, each as measured when the stage was computed (stored in the "
      "cached archives, so a cache hit reports the original time). The paper's minutes are from a "
      "2008 quad-core Xeon; ours are from the machine in the provenance.");
  notes.push_back(fmt::format(
      "Relight: median of {} relights of the first evaluation light; C++ wall time (light "
      "projection excluded) and OpenCL kernel time on {}. The paper reports frame rates "
      "including BTF shading, not relight times, so there is no paper number to compare; our "
      "frame rates are measured by `prtlab fps` (G-buffer, relight and BTF shading at 640 x 480) "
      "and recorded in results/fps/.",
      result.parameters.value("repeats", 0), device_label(result)));
  return notes;
}

std::string render_csv(const TableResult& result) {
  const auto& p = result.provenance;
  std::string out;
  out += fmt::format("# prtlab experiment {}: {} ({} backend vs the paper)\n",
                     to_string(result.table), caption(result.table),
                     result.parameters.value("backend", std::string(kTableBackend)));
  out += fmt::format("# git: {}{}\n", p.git_hash, p.git_dirty ? " (dirty)" : "");
  out += fmt::format("# build: {} ({})\n", p.build_type, p.compiler);
  out += fmt::format("# machine: {}, {} cores, {:.1f} GiB\n", p.cpu_model, p.cores, p.memory_gib);
  out += fmt::format("# opencl_device: {}\n", device_label(result));
  out += fmt::format("# date: {}\n", p.date_utc);
  out += fmt::format("# command: {}\n", p.command_line);
  out += fmt::format("# parameters: {}\n", result.parameters.dump());
  const auto& cols = columns();
  for (std::size_t i = 0; i < cols.size(); ++i) {
    if (i) out += ',';
    out += cols[i].name;
  }
  out += '\n';
  for (const auto& row : result.rows) {
    for (std::size_t i = 0; i < cols.size(); ++i) {
      if (i) out += ',';
      out += csv_field(cols[i].value(row));
    }
    out += '\n';
  }
  return out;
}

std::string render_markdown(const TableResult& result) {
  std::string md;
  md += fmt::format("# {} — regenerated by prtlab\n\n", caption(result.table));
  const std::string backend = result.parameters.value("backend", std::string(kTableBackend));
  const std::string reference =
      result.parameters.value("reference_backend", std::string(kReferenceBackend));
  md += fmt::format(
      "Backend `{}`{} on our stand-in scenes, each beside the paper's number (the paper's is "
      "lossless biclustering). Env {} pixels (6 x R x R), {}x{} supersampled visibility.\n\n",
      backend,
      backend == kTableBackend
          ? " (lossless biclustering of the pixel-basis transfer T, Sun et al.)"
          : "",
      result.rows.empty() ? 0 : result.rows.front().pixel_count,
      result.rows.empty() ? 0 : result.rows.front().supersampling,
      result.rows.empty() ? 0 : result.rows.front().supersampling);

  struct Line {
    std::string label;
    std::function<std::string(const SceneRow&)> ours;
    std::function<std::string(const PaperRow&)> paper;  // null: the paper has no such number
  };
  const std::vector<Line> lines = {
      {"#Vertices", [](auto& r) { return thousands(r.vertices); },
       [](auto& p) { return thousands(p.vertices); }},
      {"Local directions M", [](auto& r) { return std::to_string(r.local_count); }, nullptr},
      {"nnz(T) (M)", [](auto& r) { return fixed(r.nnz_millions, 2); },
       [](auto& p) { return fixed(p.nnz_millions, 1); }},
      {"MFLOPs (2 nnz)", [](auto& r) { return fixed(r.mflops, 1); },
       [](auto& p) { return fixed(p.mflops, 1); }},
      {"Reduced to (MFLOPs)", [](auto& r) { return fixed(r.reduced_mflops, 2); },
       [](auto& p) { return fixed(p.reduced_mflops, 1); }},
      {"Computation %", [](auto& r) { return fixed(r.computation_percent, 1); },
       [](auto& p) { return fixed(p.computation_percent, 1); }},
      {"Data size (MB)",
       [](auto& r) { return r.dense_mb < 100 ? fixed(r.dense_mb, 2) : thousands(r.dense_mb); },
       [](auto& p) { return thousands(p.data_mb); }},
      {"Reduced to (MB)", [](auto& r) { return fixed(r.reduced_mb, 1); },
       [](auto& p) { return fixed(p.reduced_mb, 1); }},
      {"Data size %", [](auto& r) { return fixed(r.data_percent, 2); },
       [](auto& p) { return fixed(p.data_percent, 2); }},
      {"Precomp. (min)", [](auto& r) { return fixed(r.precompute_minutes, 2); },
       [](auto& p) { return fixed(p.precompute_minutes, 0); }},
      {"- transfer T (min)", [](auto& r) { return fixed(r.transfer_seconds / 60.0, 2); }, nullptr},
      {"- " + backend + " (min)", [](auto& r) { return fixed(r.compress_seconds / 60.0, 2); },
       nullptr},
      {"Relight C++, " + backend + " (ms)", [](auto& r) { return fixed(r.subject.ms_cpp, 2); },
       nullptr},
      {"Relight OpenCL, " + backend + " (ms)",
       [](auto& r) { return fixed(r.subject.ms_opencl, 2); }, nullptr},
      {"Relight C++, " + reference + " (ms)",
       [](auto& r) { return fixed(r.reference_timing.ms_cpp, 2); }, nullptr},
      {"Relight OpenCL, " + reference + " (ms)",
       [](auto& r) { return fixed(r.reference_timing.ms_opencl, 2); }, nullptr},
      {"Error vs exact (max rel. L2)",
       [](auto& r) { return fmt::format("{:.1e}", r.rel_l2_error_max); }, nullptr},
      {"Frobenius error ‖T~ − T‖ / ‖T‖",
       [](auto& r) { return fmt::format("{:.1e}", r.frobenius_rel_error); }, nullptr},
      {"Lossless", [](auto& r) { return r.lossless.verdict(); }, nullptr},
      {"Avg. FPS view/light",
       [backend](auto& r) { return fmt::format("`prtlab fps {} --backend {}`", r.scene, backend); },
       [](auto& p) { return p.fps; }},
  };
  md += "| |";
  for (const auto& r : result.rows) md += fmt::format(" {} ours | paper |", r.scene);
  md += "\n|---|";
  for (std::size_t i = 0; i < result.rows.size(); ++i) md += "---:|---:|";
  md += '\n';
  for (const auto& line : lines) {
    md += "| " + line.label + " |";
    for (const auto& r : result.rows) {
      const std::string theirs = r.paper && line.paper ? line.paper(*r.paper) : "—";
      md += fmt::format(" {} | {} |", line.ours(r), theirs);
    }
    md += '\n';
  }

  md += "\n## Lossless check\n\n";
  md += fmt::format(
      "Through the public backend interface only: {} count probes per scene cover every column of "
      "T with weights (s^2+1)^i, so each output decodes to T's counts exactly, compared with "
      "relight_exact; plus {} random non-negative lights (seed {}) against the "
      "double-accumulated exact product, which must stay under {:.0e} (float rounding). See "
      "experiments/lossless_check.h. Both run on the C++ relight and, when an OpenCL device is "
      "open, again on the device relight.\n\n",
      result.rows.empty() ? 0 : result.rows.front().lossless.cpp.probes,
      result.parameters.value("lossless_random_lights", 0),
      result.parameters.value("lossless_seed", 0), kFloatRoundingBound);
  md +=
      "| scene | path | verdict | probes | values compared | mismatches | max count error | "
      "random-light max rel. error |\n";
  md += "|---|---|---|---:|---:|---:|---:|---:|\n";
  for (const auto& r : result.rows) {
    auto row = [&](const char* path, const LosslessPath& p) {
      md += fmt::format("| {} | {} | {} | {} | {} | {} | {:.2g} | {:.2g} |\n", r.scene, path,
                        r.lossless.verdict(), p.probes, p.probe_values, p.mismatches,
                        p.max_count_error, p.random_max_rel_error);
    };
    row("C++", r.lossless.cpp);
    if (r.lossless.opencl) row("OpenCL", *r.lossless.opencl);
  }

  md += "\n## Notes\n\n";
  for (const auto& n : table_notes(result)) md += "- " + n + "\n";

  const auto& p = result.provenance;
  md += "\n## How to reproduce\n\n";
  md += fmt::format(
      "`{}` (add `--force` to recompute T and the biclustering instead of loading them from the "
      "stage cache; docs/experiments.md).\n\n",
      reproduce_command(result));
  md += "## Provenance\n\n";
  md +=
      fmt::format("- git: {}{}\n", p.git_hash, p.git_dirty ? " (dirty: uncommitted changes)" : "");
  md += fmt::format("- build: {} ({}), prtlab {}\n", p.build_type, p.compiler, p.version);
  md += fmt::format("- machine: {}, {} cores, {:.1f} GiB ({})\n", p.cpu_model, p.cores,
                    p.memory_gib, p.hostname);
  md += fmt::format("- OpenCL device: {}\n", device_label(result));
  md += fmt::format("- date: {}\n", p.date_utc);
  md += fmt::format("- command: `{}`\n", p.command_line);
  md += fmt::format("- parameters: `{}`\n", result.parameters.dump());
  return md;
}

nlohmann::json to_json(const TableResult& result) {
  nlohmann::json rows = nlohmann::json::array();
  const auto opt = [](const std::optional<double>& v) {
    return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
  };
  for (const auto& r : result.rows) {
    nlohmann::json storage = nlohmann::json::array();
    for (const auto& c : r.storage)
      storage.push_back({{"name", c.name}, {"bytes", c.bytes}, {"layout", c.layout}});
    nlohmann::json j = {
        {"scene", r.scene},
        {"scene_file", r.scene_file.string()},
        {"vertices", r.vertices},
        {"local_directions", r.local_count},
        {"global_directions", r.pixel_count},
        {"supersampling", r.supersampling},
        {"nnz", r.nnz},
        {"nnz_millions", r.nnz_millions},
        {"mflops", r.mflops},
        {"reduced_mflops", r.reduced_mflops},
        {"computation_percent", r.computation_percent},
        {"dense_bytes", r.dense_bytes},
        {"dense_mb", r.dense_mb},
        {"reduced_bytes", r.reduced_bytes},
        {"reduced_mb", r.reduced_mb},
        {"data_percent", r.data_percent},
        {"storage", storage},
        {"precompute_minutes", r.precompute_minutes},
        {"transfer_seconds", r.transfer_seconds},
        {"backend", r.backend},
        {"reference", r.reference},
        {"compress_seconds", r.compress_seconds},
        {"frobenius_rel_error", r.frobenius_rel_error},
        {"frobenius_rel_error_stderr", r.frobenius_rel_error_stderr},
        {"max_vertex_rel_error", r.max_vertex_rel_error},
        {"transfer_cache_hit", r.transfer_cache_hit},
        {"compress_cache_hit", r.compress_cache_hit},
        {"parameters", r.params},
        {"relight_ms",
         {{"backend_cpp", r.subject.ms_cpp},
          {"backend_opencl", opt(r.subject.ms_opencl)},
          {"reference_cpp", r.reference_timing.ms_cpp},
          {"reference_opencl", opt(r.reference_timing.ms_opencl)},
          {"backend_project_light", r.ms_project_light}}},
        {"opencl_vs_cpp_rel_l2",
         {{"backend", opt(r.subject.opencl_vs_cpp_rel_l2)},
          {"reference", opt(r.reference_timing.opencl_vs_cpp_rel_l2)}}},
        {"rel_l2_error_mean", r.rel_l2_error_mean},
        {"rel_l2_error_max", r.rel_l2_error_max},
        {"evaluation_lights", r.evaluation_lights},
        {"lossless", to_json(r.lossless)},
        {"fps", nullptr},
    };
    if (r.paper) {
      const auto& p = *r.paper;
      j["paper"] = {{"vertices", p.vertices},
                    {"nnz_millions", p.nnz_millions},
                    {"mflops", p.mflops},
                    {"reduced_mflops", p.reduced_mflops},
                    {"computation_percent", p.computation_percent},
                    {"dense_mb", p.data_mb},
                    {"reduced_mb", p.reduced_mb},
                    {"data_percent", p.data_percent},
                    {"precompute_minutes", p.precompute_minutes},
                    {"fps_view_light", p.fps}};
    } else {
      j["paper"] = nullptr;
    }
    rows.push_back(std::move(j));
  }
  return {{"experiment", std::string(to_string(result.table))},
          {"caption", std::string(caption(result.table))},
          {"backend", result.parameters.value("backend", std::string(kTableBackend))},
          {"rows", rows},
          {"notes", table_notes(result)},
          {"reproduce", reproduce_command(result)},
          {"parameters", result.parameters},
          {"provenance", to_json(result.provenance)}};
}

std::vector<std::filesystem::path> write_table_files(const TableResult& result,
                                                     const std::filesystem::path& out_dir) {
  const std::string stem(to_string(result.table));
  // Render all three before writing any, so a rendering failure leaves no mixed set.
  const std::string md = render_markdown(result);
  const std::string csv = render_csv(result);
  const std::string json = to_json(result).dump(2) + "\n";
  std::vector<std::filesystem::path> files = {out_dir / (stem + ".md"), out_dir / (stem + ".csv"),
                                              out_dir / (stem + ".json")};
  write_text_atomically(files[0], md);
  write_text_atomically(files[1], csv);
  write_text_atomically(files[2], json);
  return files;
}

}  // namespace prt::experiments
