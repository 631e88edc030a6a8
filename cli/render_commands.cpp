// prtlab render commands (filled in by the issue that adds them).
#include "commands.h"

namespace prt::cli {

void add_render_commands(CLI::App& /*app*/) {}

}  // namespace prt::cli
