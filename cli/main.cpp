#include <tbb/global_control.h>

#include <cstdio>
#include <exception>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"
#include "prtlab/base/build_info.h"
#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/base/progress.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/distributed/communicator.h"
#include "prtlab/storage/atomic_file.h"

namespace {

// The commands that spread their work over MPI ranks (docs/distributed.md); any other command
// launched on several ranks would run once per rank, each writing the same files.
bool runs_distributed(const CLI::App& app) {
  for (const CLI::App* sub : app.get_subcommands()) {
    if (sub->get_name() == "precompute" || sub->get_name() == "compress") return true;
    if (sub->get_name() == "experiment")
      for (const CLI::App* what : sub->get_subcommands())
        if (what->get_name() == "run" || what->get_name() == "all") return true;
  }
  return false;
}

int run(int argc, char** argv);

}  // namespace

int main(int argc, char** argv) {
  std::optional<prt::DistributedSession> session;
  try {
    session.emplace(argc, argv);
  } catch (const prt::Error& e) {
    std::fprintf(stderr, "prtlab: error: %s\n", e.what());
    return 1;
  }
  const int code = run(argc, argv);
  // An error on one rank would leave the others waiting for it in a collective.
  if (code != 0 && prt::Communicator::world().distributed()) prt::DistributedSession::abort(code);
  return code;
}

namespace {

int run(int argc, char** argv) {
  using namespace prt;
  cli::set_command_line(argc, argv);
  remove_temporaries_on_signal();
  CLI::App app{"prtlab: compare compressors of precomputed radiance transfer", "prtlab"};
  app.require_subcommand(1);
  app.set_version_flag("--version", fmt::format("prtlab {} ({}, {})", build_info().version,
                                                build_info().git_hash, build_info().build_type));
  auto& g = cli::global_options();
  app.add_flag("-q,--quiet", g.quiet, "No progress bars or info messages");
  app.add_flag("-v,--verbose", g.verbose, "Debug messages");
  app.add_option("--device", g.device,
                 "OpenCL device: gpu, cpu, pocl, nvidia, P:D (platform:device) or a name substring "
                 "(default: $PRTLAB_DEVICE, else the first GPU, else PoCL's CPU device)");
  app.add_flag("--strict-device", g.strict_device,
               "Fail instead of falling back when the device is not found");
  app.add_flag("--no-opencl", g.no_opencl, "Run the C++ reference paths only");
  app.add_option("--threads", g.threads,
                 "Worker threads of this process (default: every core; on several MPI ranks, "
                 "per rank)")
      ->check(CLI::Range(1, 4096));
  std::optional<tbb::global_control> thread_limit;
  std::vector<std::string> plugins;
  app.add_option("--plugin", plugins,
                 "Load compressor backends from a plugin library (repeatable; see "
                 "docs/adding-a-compressor.md)")
      ->type_name("PATH.so")
      ->allow_extra_args(false);
  // Global options are accepted after the subcommand too (`prtlab list --plugin q8.so`).
  app.fallthrough();
  // Runs after parsing and before any subcommand's callback, so every command sees the plugins'
  // backends; a plugin that fails to load stops the command with load_plugin()'s reason.
  app.parse_complete_callback([&] {
    if (g.quiet) {
      Progress::set_quiet(true);
      set_log_level(LogLevel::kWarn);
    }
    if (g.verbose) set_log_level(LogLevel::kDebug);
    if (g.threads > 0)
      thread_limit.emplace(tbb::global_control::max_allowed_parallelism,
                           static_cast<std::size_t>(g.threads));
    for (const auto& path : plugins) load_plugin(path);
    const Communicator& world = Communicator::world();
    if (world.distributed() && !runs_distributed(app))
      throw ParameterError(fmt::format(
          "running on {} MPI ranks: only `prtlab precompute`, `prtlab compress` and `prtlab "
          "experiment run|all` spread over ranks; run this command without mpirun",
          world.size()));
    // Only the root prints progress bars and info lines; the others say what they do through
    // their [rank r/N] progress lines.
    if (world.distributed() && !world.is_root()) Progress::set_quiet(true);
  });

  cli::add_scene_commands(app);
  cli::add_env_commands(app);
  cli::add_transfer_commands(app);
  cli::add_backend_commands(app);
  cli::add_experiment_commands(app);
  cli::add_btf_commands(app);
  cli::add_render_commands(app);
  cli::add_image_commands(app);
  cli::add_sh_commands(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11 reads an unknown command as a stray argument and says only that a subcommand is
    // required; name the word that was not one, and the commands that are.
    if (const auto unknown = cli::unknown_command(app)) {
      std::fprintf(stderr, "prtlab: error: %s\n", unknown->c_str());
      return e.get_exit_code();
    }
    return app.exit(e);
  } catch (const prt::Error& e) {
    if (Communicator::world().distributed())
      std::fprintf(stderr, "prtlab: error (rank %d): %s\n", Communicator::world().rank(), e.what());
    else
      std::fprintf(stderr, "prtlab: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "prtlab: unexpected error: %s\n", e.what());
    return 3;
  }
  return 0;
}

}  // namespace
