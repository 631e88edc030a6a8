#include "commands.h"

namespace prt::cli {
void add_env_commands(CLI::App& app) { app.add_subcommand("env", "Environment maps: inspect and resample")->require_subcommand(1); }
}  // namespace prt::cli
