// The parameter block of every backend's README is what the registry says: for each registered
// backend (built-in and test-only), `prtlab-test list --markdown NAME` must stand verbatim
// between the README's params markers. A parameter added, renamed or redocumented without
// regenerating the pages fails here with the block to paste and the command that writes it.
// Also: scripts/gen_backend_docs.py restores a stale block and refuses a README without markers.
#include <gtest/gtest.h>

#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <string>

#include "prtlab/compress/compressor_registry.h"
#include "support/cli_runner.h"
#include "support/temp_dir.h"

namespace prt {
namespace {
namespace fs = std::filesystem;
using prt::testing::run_cli;
using prt::testing::slurp_file;

constexpr std::string_view kBegin = "<!-- params:begin -->\n";
constexpr std::string_view kEnd = "<!-- params:end -->";
constexpr const char* kRegenerate = "python3 scripts/gen_backend_docs.py";
const fs::path kSource = PRTLAB_SOURCE_DIR;

// A backend's page lives in its folder, whichever of the two kinds of backend folder it is.
std::optional<fs::path> readme_of(const std::string& backend, const fs::path& root = kSource) {
  for (const char* folder : {"compressors", "tests/backends"}) {
    const fs::path p = root / folder / backend / "README.md";
    if (fs::exists(p)) return p;
  }
  return std::nullopt;
}

// The text between the markers; nullopt when either is missing or they come in the wrong order.
std::optional<std::string> params_block(const std::string& text) {
  const auto begin = text.find(kBegin);
  if (begin == std::string::npos) return std::nullopt;
  const auto end = text.find(kEnd, begin + kBegin.size());
  if (end == std::string::npos) return std::nullopt;
  return text.substr(begin + kBegin.size(), end - begin - kBegin.size());
}

std::string python_command(const fs::path& root) {
  return "python3 \"" + (kSource / "scripts" / "gen_backend_docs.py").string() + "\" --cli \"" +
         std::string(PRTLAB_TEST_CLI_PATH) + "\" --root \"" + root.string() + "\"";
}

class BackendDocs : public ::testing::TestWithParam<std::string> {
 protected:
  prt::testing::TempDir tmp_{"backend_docs"};
};

TEST_P(BackendDocs, ReadmeHoldsTheGeneratedParameterBlock) {
  const std::string& backend = GetParam();
  const auto r = run_cli("list --markdown " + backend, tmp_.path(), {}, PRTLAB_TEST_CLI_PATH);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string& expected = r.out;
  ASSERT_NE(expected.find("| `seed` (shared) |"), std::string::npos) << expected;
  for (const auto& spec : CompressorRegistry::instance().get(backend).params)
    EXPECT_NE(expected.find("| `" + spec.key + "` |"), std::string::npos)
        << "parameter " << spec.key << " missing from\n"
        << expected;

  const auto readme = readme_of(backend);
  ASSERT_TRUE(readme) << backend << " has no README.md in compressors/" << backend
                      << "/ or tests/backends/" << backend << "/";
  const auto block = params_block(slurp_file(*readme));
  ASSERT_TRUE(block) << readme->string() << " has no '" << kBegin.substr(0, kBegin.size() - 1)
                     << "' ... '" << kEnd
                     << "' block: put the two markers where the parameter table belongs and run "
                     << kRegenerate;
  EXPECT_TRUE(*block == expected) << readme->string()
                                  << ": the parameter block is stale. Regenerate it with\n    "
                                  << kRegenerate << "\n(after building), or paste:\n"
                                  << expected;
}

INSTANTIATE_TEST_SUITE_P(Registry, BackendDocs,
                         ::testing::ValuesIn(CompressorRegistry::instance().names()),
                         [](const ::testing::TestParamInfo<std::string>& p) {
                           std::string s = p.param;
                           for (char& c : s)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return s;
                         });

// The script on a copy of the READMEs: a stale block comes back, a missing marker is an error.
class BackendDocsScript : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const auto& name : CompressorRegistry::instance().names()) {
      const auto readme = readme_of(name);
      ASSERT_TRUE(readme) << name;
      const fs::path copy = root_ / fs::relative(*readme, kSource);
      fs::create_directories(copy.parent_path());
      fs::copy_file(*readme, copy);
      copies_[name] = copy;
    }
  }
  int run_script(const std::string& extra = {}) const {
    const std::string cmd = python_command(root_) + " " + extra + " >\"" +
                            (tmp_.path() / "out.txt").string() + "\" 2>&1";
    const int status = std::system(cmd.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  std::string output() const { return slurp_file(tmp_.path() / "out.txt"); }
  static void write(const fs::path& p, const std::string& text) {
    std::ofstream(p, std::ios::binary) << text;
  }

  prt::testing::TempDir tmp_{"backend_docs_script"};
  fs::path root_ = tmp_.path() / "root";
  std::map<std::string, fs::path> copies_;
};

TEST_F(BackendDocsScript, RestoresAStaleBlockAndCheckReportsIt) {
  const fs::path page = copies_.at("uncompressed");
  const std::string original = slurp_file(page);
  const auto block = params_block(original);
  ASSERT_TRUE(block);
  std::string stale = original;
  stale.replace(stale.find(*block), block->size(), "| `old` | hand-written |\n");
  write(page, stale);

  EXPECT_EQ(run_script("--check"), 1) << output();
  EXPECT_NE(output().find("stale"), std::string::npos) << output();
  EXPECT_EQ(slurp_file(page), stale) << "--check wrote the file";
  EXPECT_EQ(run_script(), 0) << output();
  EXPECT_EQ(slurp_file(page), original);
  EXPECT_EQ(run_script("--check"), 0) << output();
}

TEST_F(BackendDocsScript, ReadmeWithoutMarkersIsAnError) {
  const fs::path page = copies_.at("uncompressed");
  std::string text = slurp_file(page);
  text.erase(text.find(kEnd), kEnd.size());
  write(page, text);
  EXPECT_EQ(run_script(), 1) << output();
  EXPECT_NE(output().find(page.string()), std::string::npos) << output();
}

TEST(BackendDocsCli, MarkdownOfAnUnknownBackendIsAnError) {
  prt::testing::TempDir tmp("backend_docs_cli");
  const auto r = run_cli("list --markdown no-such-backend", tmp.path(), {}, PRTLAB_TEST_CLI_PATH);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no-such-backend"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace prt
