#pragma once
// Runs the prtlab executable as a user would (through the shell), capturing exit code, stdout
// and stderr, for the CLI tests.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace prt::testing {

struct CliResult {
  int exit_code = -1;
  std::string out, err;
};

inline std::string slurp_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// `env` is prepended to the command line (e.g. "PRTLAB_CACHE=/tmp/x "); output files go to `dir`.
/// `program` is the prtlab executable (the test build with the test-only backends is
/// PRTLAB_TEST_CLI_PATH).
inline CliResult run_cli(const std::string& args, const std::filesystem::path& dir,
                         const std::string& env = {}, const std::string& program = PRTLAB_CLI_PATH) {
  const auto out = dir / "stdout.txt", err = dir / "stderr.txt";
  const std::string cmd = env + "\"" + program + "\" " + args + " >\"" +
                          out.string() + "\" 2>\"" + err.string() + "\"";
  const int status = std::system(cmd.c_str());
  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp_file(out);
  r.err = slurp_file(err);
  return r;
}

}  // namespace prt::testing
