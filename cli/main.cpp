#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "commands.h"
#include "prtlab/base/build_info.h"
#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/base/progress.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/storage/atomic_file.h"

int main(int argc, char** argv) {
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
    for (const auto& path : plugins) load_plugin(path);
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
    std::fprintf(stderr, "prtlab: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "prtlab: unexpected error: %s\n", e.what());
    return 3;
  }
  return 0;
}
