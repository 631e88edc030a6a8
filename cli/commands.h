#pragma once
// Each command group lives in its own file and adds itself to the app here. A group's
// add_* function creates its subcommands and their callbacks; callbacks throw prt::Error on
// bad input and main() prints it.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "prtlab/opencl/cl_context.h"

namespace prt::cli {

/// Options every command understands.
struct GlobalOptions {
  bool quiet = false;
  bool verbose = false;
  std::string device;          ///< --device (else $PRTLAB_DEVICE, else first GPU, else PoCL)
  bool strict_device = false;  ///< --strict-device: fail instead of falling back
  bool no_opencl = false;      ///< --no-opencl: C++ reference paths only
  int threads = 0;             ///< --threads: worker threads (0: every core TBB sees)
};
GlobalOptions& global_options();

/// Print a JSON object to stdout (2-space indent) with a "prtlab" provenance block added.
void print_json(nlohmann::json j);
/// The provenance block: version, git hash, build type, machine, UTC time, command line.
nlohmann::json provenance();
void set_command_line(int argc, char** argv);

void add_scene_commands(CLI::App& app);
void add_env_commands(CLI::App& app);
void add_transfer_commands(CLI::App& app);
void add_backend_commands(CLI::App& app);
void add_experiment_commands(CLI::App& app);
void add_btf_commands(CLI::App& app);
void add_render_commands(CLI::App& app);
void add_image_commands(CLI::App& app);
void add_sh_commands(CLI::App& app);

/// After a failed parse: "unknown command 'X' for 'prtlab env' (commands: ...)" when the deepest
/// command that was parsed has subcommands and the next word was none of them.
std::optional<std::string> unknown_command(const CLI::App& app);

/// The OpenCL context the global options ask for; nullopt with --no-opencl or without OpenCL.
std::optional<ClContext> open_device_from_options();

}  // namespace prt::cli
