// prtlab experiment table1|table2|run|report|all|list: the papers' tables and the experiment files
// (docs/experiments.md).
#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <functional>

#include "commands.h"
#include "experiment_report.h"
#include "experiment_run.h"
#include "experiment_spec.h"
#include "material_table.h"
#include "paper_table.h"
#include "plot_script.h"
#include "prtlab/base/build_info.h"
#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/distributed/communicator.h"
#include "stability_suite.h"
#include "table_report.h"

namespace prt::cli {
namespace {

struct TableCli {
  std::string table;
  std::vector<std::string> scenes;
  std::string out = "results";
  bool force = false;
  bool json = false;
  bool plot = true;
  std::vector<std::string> params;
  std::string backend = experiments::kTableBackend;
  std::string reference = experiments::kReferenceBackend;
  int repeats = 20;
  int lights = 8;
};

std::string command_line_from_provenance() {
  return provenance().value("command", std::string());
}

void plot(const std::filesystem::path& out_dir, bool quiet) {
  (void)experiments::run_plot_script("plot_tables.py", experiments::shell_quote(out_dir.string()),
                                     quiet);
}

void run_table(const TableCli& o) {
  using namespace experiments;
  const PaperTable table = parse_paper_table(o.table);
  const auto& g = global_options();
  TableOptions opt;
  opt.scenes = o.scenes;
  opt.params = ParamSet::parse_assignments(o.params);
  opt.backend = o.backend;
  opt.reference = o.reference;
  opt.force = o.force;
  opt.repeats = o.repeats;
  opt.evaluation_lights = o.lights;
  opt.show_progress_bars = !g.quiet;
  opt.command_line = command_line_from_provenance();
  if (!g.quiet)
    opt.on_progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  // Validate the scenes and backend parameters before opening a device (a typo must cost
  // nothing); run_paper_table validates them again, cheaply.
  (void)resolve_table_scenes(table, opt.scenes);
  const auto& entry = CompressorRegistry::instance().get(opt.backend);
  (void)ParamSet(opt.backend, entry.params, opt.params);
  (void)CompressorRegistry::instance().get(opt.reference);
  auto ctx = open_device_from_options();
  opt.device = ctx ? &*ctx : nullptr;

  const TableResult result = run_paper_table(table, opt);
  const auto files = write_table_files(result, o.out);
  if (o.plot) plot(o.out, g.quiet);
  if (o.json) {
    auto j = to_json(result);
    nlohmann::json paths = nlohmann::json::array();
    for (const auto& f : files) paths.push_back(f.string());
    j["files"] = paths;
    print_json(std::move(j));
    return;
  }
  std::printf("%s", render_markdown(result).c_str());
  std::printf("\nwrote");
  for (const auto& f : files) std::printf(" %s", f.string().c_str());
  std::printf("\n");
}

struct RunCli {
  std::string experiment;
  std::string variant;
  bool quick = false;
  std::string out = "results";
  bool force = false;
  bool recompute = false;
  bool plot = true;
  bool json = false;
  std::vector<std::string> scenes;
  std::size_t max_points = experiments::kDefaultMaxPoints;
};

std::vector<std::string> registered_backends() {
  return CompressorRegistry::instance().names();
}

std::string variant_of(const RunCli& o) {
  if (o.quick && !o.variant.empty() && o.variant != "quick")
    throw ParameterError("give either --quick or --variant");
  return o.quick ? "quick" : o.variant;
}

experiments::RunSummary run_one(const std::filesystem::path& file, const std::string& variant,
                                const RunCli& o, ClContext* device) {
  const auto& g = global_options();
  const auto spec = experiments::parse_experiment(file, variant, registered_backends());
  experiments::RunOptions ro;
  ro.out_root = o.out;
  ro.force = o.force;
  ro.recompute = o.recompute;
  ro.device = device;
  ro.scenes = o.scenes;
  ro.max_points = o.max_points;
  ro.show_progress_bars = !g.quiet;
  ro.command_line = command_line_from_provenance();
  ro.comm = &Communicator::world();
  if (!g.quiet)
    ro.on_progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  auto summary = experiments::run_experiment(spec, ro);
  if (ro.comm->is_root()) experiments::write_experiment_report(summary.folder, o.plot, g.quiet);
  return summary;
}

// A run with failed points has not measured what its file asks for: the command fails with a
// one-line summary (printed even with -q) after the result files are written.
void check_run(const experiments::RunSummary& s) {
  if (s.failed == 0 || !Communicator::world().is_root()) return;
  throw Error(fmt::format(
      "{}: {} point{} failed, {} measured{} (first: {}; every failure is in {})", s.folder.string(),
      s.failed, s.failed == 1 ? "" : "s", s.points, s.complete ? "" : "; not marked complete",
      s.first_failure, (s.folder / "README.md").string()));
}

void print_run(const experiments::RunSummary& s, bool json) {
  if (!Communicator::world().is_root()) return;  // the root wrote the files
  if (json) {
    auto j = s.result;
    j["folder"] = s.folder.string();
    j["resumed"] = s.resumed;
    print_json(std::move(j));
    return;
  }
  std::printf("wrote %s (README.md, result.json, points.csv, errors.csv%s)\n",
              s.folder.string().c_str(),
              std::filesystem::exists(s.folder / "images") ? ", images/" : "");
}

// A material table (kind "material_table", material_table.h) runs its own way.
nlohmann::json run_table_file(const std::filesystem::path& file, const std::string& variant,
                              const RunCli& o, ClContext* device) {
  experiments::MaterialTableOptions mo;
  mo.out_root = o.out;
  mo.variant = variant;
  mo.force = o.force;
  mo.device = device;
  mo.command_line = command_line_from_provenance();
  mo.show_progress = !global_options().quiet;
  if (!o.scenes.empty()) mo.scene = o.scenes.front();
  return experiments::run_material_table(file, mo);
}

// The stability suite (kind "stability", stability_suite.h) runs its own way too.
nlohmann::json run_stability_file(const std::filesystem::path& file, const std::string& variant,
                                  const RunCli& o, const std::vector<std::string>& cases = {}) {
  experiments::StabilityOptions so;
  so.out_root = o.out;
  so.variant = variant;
  so.cases = cases;
  so.command_line = command_line_from_provenance();
  so.show_progress = !global_options().quiet;
  return experiments::run_stability_suite(file, so);
}

// Material tables, the stability suite and the paper's tables run on one process.
void refuse_on_ranks(const std::filesystem::path& file) {
  if (Communicator::world().distributed())
    throw ParameterError(fmt::format(
        "{}: material tables, the stability suite and the paper's tables run on one process; "
        "run it without mpirun (experiment files of points spread over ranks)",
        file.string()));
}

void run_file(const RunCli& o) {
  const auto file = experiments::resolve_experiment(o.experiment);
  const std::string variant = variant_of(o);
  if (experiments::is_stability_suite(file) || experiments::is_material_table(file))
    refuse_on_ranks(file);
  if (experiments::is_stability_suite(file)) {
    const auto r = run_stability_file(file, variant, o);
    if (o.json)
      print_json(r);
    else
      std::printf("wrote %s (README.md, result.json, cases.csv)\n",
                  r.at("folder").get<std::string>().c_str());
    return;
  }
  if (experiments::is_material_table(file)) {
    auto ctx = open_device_from_options();
    const auto r = run_table_file(file, variant, o, ctx ? &*ctx : nullptr);
    if (o.json)
      print_json(r);
    else
      std::printf("wrote %s (README.md, result.json, table.csv, images/)\n",
                  r.at("folder").get<std::string>().c_str());
    return;
  }
  // Parse and size before opening a device: a typo in the file costs nothing.
  experiments::check_point_budget(
      experiments::parse_experiment(file, variant, registered_backends()), o.max_points);
  auto ctx = open_device_from_options();
  const auto summary = run_one(file, variant, o, ctx ? &*ctx : nullptr);
  print_run(summary, o.json);
  check_run(summary);
}

void run_all(const RunCli& o) {
  const std::string variant = variant_of(o);
  const bool quiet = global_options().quiet;
  auto ctx = open_device_from_options();
  // On several ranks the files of points are spread over them; what runs on one process (the
  // paper's tables, material tables, the stability suite) runs on the root while the others go
  // on to the next file of points.
  const bool root = Communicator::world().is_root();
  // The paper's tables first (--quick: on the bunny alone, into <out>/tables-quick/ so that the
  // full tables are never replaced by partial ones), then every experiment file.
  for (const char* name : {"table1", "table2"}) {
    TableCli t;
    t.table = name;
    t.out = o.quick ? (std::filesystem::path(o.out) / "tables-quick").string() : o.out;
    t.force = o.recompute;
    t.plot = o.plot;
    if (o.quick) t.scenes = {"bunny"};
    if (!o.scenes.empty()) t.scenes = o.scenes;
    if (!root) continue;
    if (!quiet) std::fprintf(stderr, "== experiment %s\n", name);
    run_table(t);
  }
  // A file of its own kind (a material table, the stability suite): skipped when it lacks the
  // variant or its folder is complete (without --force), else run.
  auto run_own_kind = [&](const std::filesystem::path& file,
                          const std::vector<std::string>& variants,
                          const std::function<std::filesystem::path()>& folder_of,
                          const std::function<nlohmann::json()>& run) {
    if (!root) return;
    if (!variant.empty() &&
        std::find(variants.begin(), variants.end(), variant) == variants.end()) {
      if (!quiet)
        std::fprintf(stderr, "== experiment %s: skipped (no [variant.%s])\n",
                     file.stem().string().c_str(), variant.c_str());
      return;
    }
    const auto folder = folder_of();
    if (!o.force && std::filesystem::exists(folder / ".complete")) {
      if (!quiet)
        std::fprintf(stderr, "== experiment %s: %s is complete (--force reruns it)\n",
                     file.stem().string().c_str(), folder.string().c_str());
      return;
    }
    if (!quiet) std::fprintf(stderr, "== experiment %s\n", file.stem().string().c_str());
    const auto r = run();
    std::printf("wrote %s\n", r.at("folder").get<std::string>().c_str());
  };
  // One file's failure (a backend it names is not loaded, a scene missing) does not stop the
  // others; the command fails at the end, naming each.
  std::vector<std::string> failures;
  const auto files = experiments::experiment_files();
  for (const auto& file : files) {
    bool collective_done = false;  // the ranks' part of this file is behind them
    try {
      if (experiments::is_stability_suite(file)) {
        run_own_kind(
            file, experiments::stability_suite_variants(file),
            [&] { return experiments::stability_suite_folder(file, variant, o.out); },
            [&] { return run_stability_file(file, variant, o); });
        continue;
      }
      if (experiments::is_material_table(file)) {
        run_own_kind(
            file, experiments::material_table_variants(file),
            [&] { return experiments::material_table_folder(file, variant, o.out); },
            [&] { return run_table_file(file, variant, o, ctx ? &*ctx : nullptr); });
        continue;
      }
      const auto variants = experiments::experiment_variants(file);
      if (!variant.empty() &&
          std::find(variants.begin(), variants.end(), variant) == variants.end()) {
        if (!quiet)
          std::fprintf(stderr, "== experiment %s: skipped (no [variant.%s])\n",
                       file.stem().string().c_str(), variant.c_str());
        continue;
      }
      const auto spec = experiments::parse_experiment(file, variant, registered_backends());
      const auto folder = experiments::result_folder(spec, o.out);
      bool complete = std::filesystem::exists(folder / ".complete");
      // The root's folder decides for every rank (the results may live on its filesystem only).
      if (Communicator::world().distributed())
        complete =
            Communicator::world().broadcast({static_cast<std::uint8_t>(complete && root)})[0] != 0;
      if (!o.force && complete) {
        if (!quiet)
          std::fprintf(stderr, "== experiment %s: %s is complete (--force reruns it)\n",
                       file.stem().string().c_str(), folder.string().c_str());
        continue;
      }
      if (!quiet)
        std::fprintf(stderr, "== experiment %s%s\n", file.stem().string().c_str(),
                     variant.empty() ? "" : (" (" + variant + ")").c_str());
      const auto summary = run_one(file, variant, o, ctx ? &*ctx : nullptr);
      collective_done = true;
      print_run(summary, false);
      check_run(summary);
    } catch (const Error& e) {
      // On several ranks a file one rank gave up on inside its collectives would leave the
      // others waiting there: that error ends the run (every rank). Failed points, reported by
      // the root after the ranks' part, do not.
      if (Communicator::world().distributed() && !collective_done) throw;
      std::fprintf(stderr, "prtlab: error: %s\n", e.what());
      failures.push_back(file.string());
    }
  }
  if (!failures.empty()) {
    std::string list;
    for (const auto& f : failures) list += (list.empty() ? "" : ", ") + f;
    throw Error(fmt::format("experiment all: {} of {} experiment files failed: {}", failures.size(),
                            files.size(), list));
  }
}

void list_experiments(bool json) {
  nlohmann::json list = nlohmann::json::array();
  for (const auto& file : experiments::experiment_files()) {
    experiments::ExperimentSpec spec;
    if (experiments::is_stability_suite(file)) {
      list.push_back(
          {{"name", file.stem().string()},
           {"title", "numerical-stability suite (docs/experiments.md \"Stability suite\")"},
           {"file", file.string()},
           {"kind", "stability"},
           {"variants", experiments::stability_suite_variants(file)}});
      continue;
    }
    if (experiments::is_material_table(file)) {
      list.push_back({{"name", file.stem().string()},
                      {"title", "material table (docs/experiments.md \"Material tables\")"},
                      {"file", file.string()},
                      {"kind", "material_table"},
                      {"variants", experiments::material_table_variants(file)}});
      continue;
    }
    try {
      spec = experiments::parse_experiment(file, "", registered_backends());
    } catch (const Error& e) {
      list.push_back({{"name", file.stem().string()},
                      {"title", std::string("(cannot be parsed: ") + e.what() + ")"},
                      {"file", file.string()},
                      {"kind", "unknown"},
                      {"variants", nlohmann::json::array()}});
      continue;
    }
    list.push_back({{"name", spec.name},
                    {"title", spec.title},
                    {"file", file.string()},
                    {"kind", experiments::to_string(spec.kind)},
                    {"variants", experiments::experiment_variants(file)}});
  }
  if (json) {
    print_json({{"experiments", list}});
    return;
  }
  std::printf("table1      the central paper's Table I (prtlab experiment table1)\n");
  std::printf("table2      the central paper's Table II (prtlab experiment table2)\n");
  for (const auto& e : list) {
    std::string v;
    for (const auto& x : e["variants"]) v += (v.empty() ? "" : ", ") + x.get<std::string>();
    std::printf("%-11s %s [%s; variants: %s] %s\n", e["name"].get<std::string>().c_str(),
                e["title"].get<std::string>().c_str(), e["kind"].get<std::string>().c_str(),
                v.empty() ? "none" : v.c_str(), e["file"].get<std::string>().c_str());
  }
}

void add_run_options(CLI::App* c, RunCli& o) {
  c->add_flag("--quick", o.quick, "Run the file's [variant.quick] (seconds to minutes)");
  c->add_option("--out", o.out, "Root of the result folders")->capture_default_str();
  c->add_flag("--force", o.force, "Overwrite a complete result folder");
  c->add_flag("--recompute", o.recompute,
              "Recompute every stage (T, compressions, points) instead of using the stage cache");
  c->add_option("--scenes", o.scenes, "Replace the experiment's scenes (names or .toml paths)")
      ->delimiter(',');
  c->add_flag("!--no-plot", o.plot, "Do not run scripts/plot_experiment.py");
  c->add_option("--max-points", o.max_points,
                "Refuse a file that plans more points than this (a grid typo costs nothing)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

}  // namespace

void add_experiment_commands(CLI::App& app) {
  auto* exp = app.add_subcommand("experiment",
                                 "Regenerate the papers' tables: table1, table2; run experiment "
                                 "files; the stability suite (docs/experiments.md)");
  exp->require_subcommand(1);
  for (const char* name : {"table1", "table2"}) {
    auto o = std::make_shared<TableCli>();
    o->table = name;
    const bool t1 = std::string_view(name) == "table1";
    auto* c = exp->add_subcommand(
        name, t1 ? "The paper's Table I (bunny, armor, chair, temple) with the bicluster backend"
                 : "The paper's Table II (bunny at 3,286 / 12,380 / 47,960 vertices)");
    c->add_option("--scenes", o->scenes,
                  "Comma-separated scene names or .toml paths (default: the table's scenes)")
        ->delimiter(',');
    c->add_option("--out", o->out, "Output directory for <table>.md/.csv/.json/.png")
        ->capture_default_str();
    c->add_flag("--force", o->force,
                "Recompute T and the compressions instead of loading them from the stage cache");
    c->add_flag("--json", o->json, "Print the result as JSON (docs/cli.md)");
    c->add_option("--backend,-b", o->backend,
                  "The backend the table measures (default bicluster, the paper's; any registered "
                  "one, a --plugin's too)");
    c->add_option("--reference", o->reference,
                  "The timing reference backend (default uncompressed, the exact product)");
    c->add_option("--param,-p", o->params, "Parameter of the backend key=value (repeatable)");
    c->add_option("--repeats", o->repeats, "Timed relights per backend (median reported)")
        ->check(CLI::Range(1, 100000))
        ->capture_default_str();
    c->add_option("--lights", o->lights, "Evaluation lights for the error (1-8)")
        ->check(CLI::Range(1, 8))
        ->capture_default_str();
    c->add_flag("!--no-plot", o->plot, "Do not run scripts/plot_tables.py");
    c->callback([o] { run_table(*o); });
  }

  auto ro = std::make_shared<RunCli>();
  auto* run = exp->add_subcommand(
      "run", "Run an experiment file (experiments/<name>.toml) into results/<name>/");
  run->add_option("experiment", ro->experiment, "Experiment name (prtlab experiment list) or path")
      ->required();
  run->add_option("--variant", ro->variant, "A [variant.NAME] of the file (quick, full)");
  add_run_options(run, *ro);
  run->add_flag("--json", ro->json, "Print result.json");
  run->callback([ro] { run_file(*ro); });

  auto rep = std::make_shared<std::pair<std::string, bool>>("", true);
  auto* report = exp->add_subcommand(
      "report", "Redraw a result folder's README.md and plots from its result.json");
  report->add_option("folder", rep->first, "A result folder (results/fig6)")->required();
  report->add_flag("!--no-plot", rep->second, "Only README.md");
  report->callback([rep] {
    experiments::write_experiment_report(rep->first, rep->second, global_options().quiet);
    std::printf("wrote %s/README.md\n", rep->first.c_str());
  });

  auto ao = std::make_shared<RunCli>();
  auto* all = exp->add_subcommand(
      "all", "Regenerate every table and figure: table1, table2 and every experiment file");
  add_run_options(all, *ao);
  all->add_option("--variant", ao->variant, "Variant of each file that declares it");
  all->callback([ao] { run_all(*ao); });

  auto so = std::make_shared<std::pair<RunCli, std::vector<std::string>>>();
  auto* stab = exp->add_subcommand(
      "stability",
      "The numerical-stability suite: every backend and material under inputs that break "
      "numerics (experiments/stability.toml into results/stability/)");
  stab->add_flag("--quick", so->first.quick, "Run the file's [variant.quick] (seconds)");
  stab->add_option("--out", so->first.out, "Root of the result folders")->capture_default_str();
  stab->add_option("--cases", so->second, "Only these cases (comma-separated)")->delimiter(',');
  stab->add_flag("--json", so->first.json, "Print result.json");
  stab->callback([so] {
    const auto file = experiments::resolve_experiment("stability");
    const auto r = run_stability_file(file, variant_of(so->first), so->first, so->second);
    if (so->first.json)
      print_json(r);
    else
      std::printf("wrote %s (README.md, result.json, cases.csv)\n",
                  r.at("folder").get<std::string>().c_str());
  });

  auto lj = std::make_shared<bool>(false);
  auto* list = exp->add_subcommand("list", "The experiments there are");
  list->add_flag("--json", *lj, "Machine-readable");
  list->callback([lj] { list_experiments(*lj); });
}

}  // namespace prt::cli
