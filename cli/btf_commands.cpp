// prtlab btf commands (filled in by the issue that adds them).
#include "commands.h"

namespace prt::cli {

void add_btf_commands(CLI::App& /*app*/) {}

}  // namespace prt::cli
