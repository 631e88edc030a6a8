#include "commands.h"

namespace prt::cli {
void add_scene_commands(CLI::App& app) { app.add_subcommand("scene", "Scene files: inspect scenes")->require_subcommand(1); }
}  // namespace prt::cli
