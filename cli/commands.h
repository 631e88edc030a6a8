#pragma once
// Each command group lives in its own file and adds itself to the app here. A group's
// add_* function creates its subcommands and their callbacks; callbacks throw prt::Error on
// bad input and main() prints it.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <string>

namespace prt::cli {

/// Options every command understands.
struct GlobalOptions {
  bool quiet = false;
  bool verbose = false;
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

}  // namespace prt::cli
