#pragma once
// Running the repository's plot scripts (scripts/*.py) with a python3 that has matplotlib, for
// the tables and the experiment reports alike.
#include <optional>
#include <string>

namespace prt::experiments {

/// The python3 that has matplotlib: $PRTLAB_PYTHON, /usr/bin/python3, then python3 (a pyenv or
/// venv python3 on PATH often lacks it while the distribution's has it); nullopt when none does.
std::optional<std::string> python_with_matplotlib();

/// Runs scripts/<script> with `args` (already quoted) under python_with_matplotlib(); prints a
/// warning naming the command to run by hand when there is no such python or the script fails.
/// Returns whether it ran and succeeded.
bool run_plot_script(const std::string& script, const std::string& args, bool quiet);

/// Quotes `s` for /bin/sh.
std::string shell_quote(const std::string& s);

}  // namespace prt::experiments
