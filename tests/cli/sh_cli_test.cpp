// `prtlab sh hemisphere` run as a user would: the documented JSON keys, values equal to the
// library's analysis, the text naming the most redundant basis function, and clear errors for a
// bad order.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "prtlab/sphere/hemisphere_projection.h"
#include "prtlab/sphere/spherical_harmonics.h"
#include "support/cli_runner.h"

namespace prt {
namespace {

namespace fs = std::filesystem;

class ShCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("prtlab_sh_cli_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  prt::testing::CliResult run(const std::string& args) const {
    return prt::testing::run_cli(args, dir_);
  }

  fs::path dir_;
};

TEST_F(ShCli, HemisphereJsonHasTheDocumentedKeysAndTheLibrarysValues) {
  const auto r = run("sh hemisphere --order 5 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  for (const char* key : {"order", "basis_functions", "singular_values", "discard_error",
                          "most_redundant", "projections", "prtlab"}) {
    ASSERT_TRUE(j.contains(key)) << key << " missing in " << r.out;
  }
  EXPECT_EQ(j["order"], 5);
  EXPECT_EQ(j["basis_functions"], 25);

  const HemisphereAnalysis a = analyse_hemisphere_projection(5);
  const auto& sv = j["singular_values"];
  for (const char* key : {"largest", "smallest", "second_smallest", "condition_number", "all"})
    ASSERT_TRUE(sv.contains(key)) << key;
  EXPECT_DOUBLE_EQ(sv["largest"].get<double>(), a.eigenvalues[0]);
  EXPECT_DOUBLE_EQ(sv["smallest"].get<double>(), a.eigenvalues[24]);
  EXPECT_DOUBLE_EQ(sv["second_smallest"].get<double>(), a.eigenvalues[23]);
  EXPECT_LT(sv["smallest"].get<double>(), sv["second_smallest"].get<double>());
  EXPECT_EQ(sv["all"].size(), 25u);

  ASSERT_EQ(j["discard_error"].size(), 25u);
  for (int i = 0; i < 25; ++i) {
    const auto& d = j["discard_error"][i];
    EXPECT_EQ(d["index"], i);
    EXPECT_EQ(sh_index(d["l"].get<int>(), d["m"].get<int>()), i);
    EXPECT_DOUBLE_EQ(d["squared_error"].get<double>(), a.discard_error[i]);
  }
  const auto& most = j["most_redundant"];
  EXPECT_EQ(most["l"], 1);
  EXPECT_EQ(most["m"], 0);
  EXPECT_EQ(most["index"], sh_index(1, 0));

  const auto& p = j["projections"];
  const char* keys[] = {"zero_hemisphere", "odd_reflection", "even_reflection",
                        "even_reflection_same_order"};
  const int orders[] = {5, 8, 7, 5};
  const int coefficients[] = {25, 28, 28, 15};
  for (int k = 0; k < 4; ++k) {
    SCOPED_TRACE(keys[k]);
    ASSERT_TRUE(p.contains(keys[k]));
    const auto& e = p[keys[k]];
    for (const char* key : {"kind", "projection_order", "coefficients", "worst", "average",
                            "worst_rms_percent", "average_rms_percent"})
      ASSERT_TRUE(e.contains(key)) << key;
    EXPECT_EQ(e["projection_order"], orders[k]);
    EXPECT_EQ(e["coefficients"], coefficients[k]);
    EXPECT_DOUBLE_EQ(e["worst"].get<double>(), a.projections[k].worst);
    EXPECT_DOUBLE_EQ(e["average"].get<double>(), a.projections[k].average);
    EXPECT_NEAR(e["worst_rms_percent"].get<double>(), 100 * std::sqrt(e["worst"].get<double>()),
                1e-9);
    EXPECT_LE(e["average"].get<double>(), e["worst"].get<double>());
  }
}

TEST_F(ShCli, HemisphereTextNamesTheSmallestBasisFunction) {
  const auto r = run("sh hemisphere --order 5");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("smallest: l=1, m=0 (index 2)"), std::string::npos) << r.out;
  for (const char* s : {"largest singular value", "second-smallest singular value",
                        "zero_hemisphere", "odd_reflection", "even_reflection"})
    EXPECT_NE(r.out.find(s), std::string::npos) << s << " missing in " << r.out;
}

TEST_F(ShCli, ReflectionOrdersAreOptions) {
  const auto r = run("sh hemisphere --order 3 --odd-order 4 --even-order 6 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["projections"]["odd_reflection"]["projection_order"], 4);
  EXPECT_EQ(j["projections"]["even_reflection"]["projection_order"], 6);
  EXPECT_EQ(j["projections"]["even_reflection_same_order"]["projection_order"], 3);
  EXPECT_DOUBLE_EQ(
      j["projections"]["odd_reflection"]["worst"].get<double>(),
      hemisphere_projection_error(HemisphereProjectionKind::kOddReflection, 3, 4).worst);
  // Defaults above the paper's orders follow the signal order.
  const auto r9 = run("sh hemisphere --order 9 --json");
  ASSERT_EQ(r9.exit_code, 0) << r9.err;
  EXPECT_EQ(nlohmann::json::parse(r9.out)["projections"]["odd_reflection"]["projection_order"], 9);
}

TEST_F(ShCli, BadOrdersExitOneWithAClearMessage) {
  for (const std::string args :
       {"sh hemisphere --order 0", "sh hemisphere --order 11", "sh hemisphere --order -3"}) {
    const auto r = run(args);
    EXPECT_EQ(r.exit_code, 1) << args;
    EXPECT_NE(r.err.find("--order must be in [1, 10]"), std::string::npos) << r.err;
  }
  const auto low = run("sh hemisphere --order 5 --odd-order 4");
  EXPECT_EQ(low.exit_code, 1);
  EXPECT_NE(low.err.find("at least --order"), std::string::npos) << low.err;
  const auto high = run("sh hemisphere --order 5 --even-order 12");
  EXPECT_EQ(high.exit_code, 1);
  EXPECT_NE(high.err.find("--even-order must be in [1, 10]"), std::string::npos) << high.err;
  const auto missing = run("sh hemisphere");
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.err.find("--order"), std::string::npos) << missing.err;
}

}  // namespace
}  // namespace prt
