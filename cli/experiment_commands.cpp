// prtlab experiment commands (filled in by the issue that adds them).
#include "commands.h"

namespace prt::cli {

void add_experiment_commands(CLI::App& /*app*/) {}

}  // namespace prt::cli
