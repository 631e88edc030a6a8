// prtlab experiment table1|table2: regenerate the central paper's tables (docs/experiments.md).
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "commands.h"
#include "paper_table.h"
#include "prtlab/base/build_info.h"
#include "prtlab/base/error.h"
#include "prtlab/compress/compressor_registry.h"
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

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// The plot script needs matplotlib; a pyenv or venv python3 on PATH often lacks it while the
// distribution's has it, so try $PRTLAB_PYTHON, then /usr/bin/python3, then python3.
std::optional<std::string> python_with_matplotlib() {
  std::vector<std::string> candidates;
  if (const char* env = std::getenv("PRTLAB_PYTHON"); env && *env) candidates.emplace_back(env);
  candidates.emplace_back("/usr/bin/python3");
  candidates.emplace_back("python3");
  for (const auto& py : candidates) {
    const std::string probe = shell_quote(py) + " -c 'import matplotlib' >/dev/null 2>&1";
    if (std::system(probe.c_str()) == 0) return py;
  }
  return std::nullopt;
}

void plot(const std::filesystem::path& out_dir, bool quiet) {
  const auto script = std::filesystem::path(build_info().source_dir) / "scripts" / "plot_tables.py";
  const std::string args = " " + shell_quote(out_dir.string());
  const auto py = python_with_matplotlib();
  if (!py || !std::filesystem::exists(script)) {
    std::fprintf(stderr,
                 "prtlab: no plot (needs python3 with matplotlib, package python3-matplotlib); "
                 "run: python3 scripts/plot_tables.py%s\n",
                 args.c_str());
    return;
  }
  const std::string cmd = shell_quote(*py) + " " + shell_quote(script.string()) + args +
                          (quiet ? " >/dev/null" : " >&2");
  if (std::system(cmd.c_str()) != 0)
    std::fprintf(stderr, "prtlab: warning: the plot script failed: %s\n", cmd.c_str());
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

}  // namespace

void add_experiment_commands(CLI::App& app) {
  auto* exp = app.add_subcommand(
      "experiment", "Regenerate the papers' tables: table1, table2 (docs/experiments.md)");
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
}

}  // namespace prt::cli
