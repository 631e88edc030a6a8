// The stability suite run from a harness file as `prtlab experiment run` would: the outcome of
// the cases whose handling is known (loaders refuse or warn by name, NaN lights are refused by
// the evaluation, NaN BTFs where they are built), no silent row, the files it writes, and a
// spec that names an unknown case refused before anything runs.
#include "stability_suite.h"

#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <string>

#include "prtlab/base/error.h"
#include "support/cli_runner.h"
#include "support/temp_dir.h"

namespace prt::experiments {
namespace {
namespace fs = std::filesystem;

class StabilitySuite : public ::testing::Test {
 protected:
  fs::path write(const std::string& text) {
    const fs::path p = tmp_.path() / "stability.toml";
    std::ofstream(p) << text;
    return p;
  }
  prt::testing::TempDir tmp_{"stability_suite"};
};

const nlohmann::json* find_row(const nlohmann::json& result, const std::string& case_name,
                               const std::string& subject) {
  for (const auto& r : result.at("rows"))
    if (r.at("case") == case_name && r.at("subject") == subject) return &r;
  return nullptr;
}

TEST_F(StabilitySuite, KnownFailureModesAreHandledByNameAndNoneIsSilent) {
  const fs::path file = write(R"(
name = "stability"
kind = "stability"
scene = "tiny-sphere-plane"
growth_scenes = ["tiny-sphere-plane"]
cases = ["radiance-near-float-max", "nan-inf-light", "nan-inf-mesh", "btf-nan-inf",
         "float-vs-double"]
backends = ["uncompressed", "bicluster"]
materials = ["full"]
)");
  ASSERT_TRUE(is_stability_suite(file));
  StabilityOptions o;
  o.out_root = tmp_.path() / "results";
  o.show_progress = false;
  const nlohmann::json r = run_stability_suite(file, o);
  const fs::path folder = r.at("folder").get<std::string>();
  for (const char* f : {"README.md", "result.json", "cases.csv", ".complete"})
    EXPECT_TRUE(fs::exists(folder / f)) << f;

  const std::map<std::pair<std::string, std::string>, std::string> expected = {
      {{"radiance-near-float-max", "environment loader"}, "refused"},
      {{"nan-inf-light", "environment loader"}, "warned"},
      {{"nan-inf-light", "uncompressed"}, "refused"},
      {{"nan-inf-light", "bicluster"}, "refused"},
      {{"nan-inf-mesh", "mesh loader (obj)"}, "refused"},
      {{"nan-inf-mesh", "mesh loader (off)"}, "refused"},
      {{"btf-nan-inf", "BTF with a NaN"}, "refused"},
      {{"btf-nan-inf", "BTF with an Inf"}, "refused"},
      {{"float-vs-double", "uncompressed"}, "ok"},
      {{"float-vs-double", "exact relight on tiny-sphere-plane"}, "ok"},
  };
  for (const auto& [key, outcome] : expected) {
    const nlohmann::json* row = find_row(r, key.first, key.second);
    ASSERT_NE(row, nullptr) << key.first << " / " << key.second;
    EXPECT_EQ(row->at("outcome"), outcome) << row->dump();
  }
  EXPECT_EQ(find_row(r, "nan-inf-light", "environment loader")
                ->at("warnings")
                .value("invalid-radiance", 0),
            1);
  EXPECT_NE(find_row(r, "nan-inf-light", "bicluster")
                ->at("detail")
                .get<std::string>()
                .find("NumericalError"),
            std::string::npos);
  // A lossless relight in float is within rounding of the double product.
  EXPECT_LT(find_row(r, "float-vs-double", "uncompressed")->at("error").get<double>(), 1e-5);
  for (const auto& row : r.at("rows")) {
    EXPECT_NE(row.at("outcome"), "silent") << row.dump();
    EXPECT_NE(row.at("outcome"), "crashed") << row.dump();
  }
}

// Relative errors against a zero reference (a black light, a black image, a black map, a black
// BTF) are undefined, said by the named warning: a finite relative error without it, as 0 / 0
// once gave, would be a silent row.
TEST_F(StabilitySuite, RelativeErrorsAgainstZeroAreWarnedNotPerfect) {
  const fs::path file = write(R"(
name = "stability"
kind = "stability"
scene = "tiny-sphere-plane"
cases = ["zero-reference"]
backends = ["uncompressed", "cpca"]
materials = ["full", "packed"]
)");
  StabilityOptions o;
  o.out_root = tmp_.path() / "results";
  o.show_progress = false;
  const nlohmann::json r = run_stability_suite(file, o);
  for (const char* subject :
       {"uncompressed", "cpca", "image error against a black image",
        "SRBF light fit of a black map", "full on a black BTF", "packed on a black BTF"}) {
    const nlohmann::json* row = find_row(r, "zero-reference", subject);
    ASSERT_NE(row, nullptr) << subject;
    EXPECT_EQ(row->at("outcome"), "warned") << row->dump();
    EXPECT_GE(row->at("warnings").value("zero-reference", 0), 1) << row->dump();
    EXPECT_NE(row->at("detail").get<std::string>().find("undefined"), std::string::npos)
        << row->dump();
  }
  // Relit to exact zeros by the lossless backend; the image's absolute error is its 0.25.
  EXPECT_EQ(find_row(r, "zero-reference", "uncompressed")->at("error").get<double>(), 0.0);
  EXPECT_NEAR(
      find_row(r, "zero-reference", "image error against a black image")->at("error").get<double>(),
      0.25, 1e-6);
}

TEST_F(StabilitySuite, AnUnknownCaseIsRefusedNamingTheFile) {
  const fs::path file = write("name = \"s\"\nkind = \"stability\"\ncases = [\"nan-light\"]\n");
  try {
    check_stability_suite(file, "");
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("nan-light"), std::string::npos) << e.what();
  }
  EXPECT_THROW(check_stability_suite(write("kind = \"stability\"\nbackend = [\"x\"]\n"), ""),
               InputError);
}

// The command: `prtlab experiment stability --cases` runs the repository's file, exit code 0
// with no silent row.
TEST_F(StabilitySuite, TheCommandRunsTheRepositorysFile) {
  const auto r = prt::testing::run_cli(
      "-q experiment stability --quick --cases nan-inf-mesh,btf-nan-inf --out \"" +
          (tmp_.path() / "out").string() + "\" --json",
      tmp_.path(), "PRTLAB_CACHE=\"" + (tmp_.path() / "cache").string() + "\" ");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("rows").size(), 4u) << r.out;
  EXPECT_TRUE(fs::exists(tmp_.path() / "out" / "stability-quick" / "README.md"));
}

}  // namespace
}  // namespace prt::experiments
