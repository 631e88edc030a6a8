// The test-only backend `coo` is wired in by its folder alone: registered under its folder's
// name, its deps.cmake applied, its kernel embedded, its relight equal to the exact product.
#include "coo/coo.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/transfer_error.h"
#include "prtlab/opencl/cl_kernel_sources.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/transfer/random_transfer.h"
#include "support/cli_runner.h"
#include "support/temp_dir.h"

namespace prt {
namespace {

TEST(CooBackend, IsRegisteredWithItsDepsAndKernel) {
  ASSERT_TRUE(CompressorRegistry::instance().contains("coo"));
  EXPECT_EQ(CompressorRegistry::instance().get("coo").origin, "built-in");
  EXPECT_TRUE(coo::built_with_its_deps());
  EXPECT_TRUE(has_kernel_source("coo"));
}

TEST(CooBackend, RelightsLikeTheExactProduct) {
  const TransferMatrix t = random_transfer(11, RandomTransferSpec{.vertices = 7,
                                                                  .grid_side = 3,
                                                                  .resolution = 2,
                                                                  .supersampling = 2,
                                                                  .density = 0.4,
                                                                  .empty_vertices = {2}});
  const CubemapLayout cubemap(2);
  const HemisphereGrid grid(3);
  const auto ct = CompressorRegistry::instance().create("coo", {})->compress(
      {t, nullptr, cubemap, grid}, Progress::null());
  std::vector<Rgb> light(t.cols());
  for (std::size_t k = 0; k < light.size(); ++k)
    light[k] = {0.5f + static_cast<float>(k % 5), 1.0f, static_cast<float>(k % 3)};
  LocalRadiance out;
  ct->relight({"pixel", light}, out);
  std::vector<Rgb> exact(t.rows());
  relight_exact(t, light, exact);
  ASSERT_EQ(out.values.size(), exact.size());
  for (std::size_t i = 0; i < exact.size(); ++i) {
    EXPECT_NEAR(out.values[i].x, exact[i].x, 1e-5f * (1.0f + exact[i].x)) << "row " << i;
    EXPECT_NEAR(out.values[i].z, exact[i].z, 1e-5f * (1.0f + exact[i].z)) << "row " << i;
  }
  EXPECT_EQ(ct->storage().total_bytes(), t.nnz() * 12);
}

// The lossy mode's declared Frobenius error is what the generic measurement finds.
TEST(CooBackend, DeclaresTheFrobeniusErrorItHas) {
  const TransferMatrix t = random_transfer(5, RandomTransferSpec{.vertices = 9,
                                                                 .grid_side = 3,
                                                                 .resolution = 3,
                                                                 .supersampling = 3,
                                                                 .density = 0.6,
                                                                 .empty_vertices = {}});
  const CubemapLayout cubemap(3);
  const HemisphereGrid grid(3);
  const auto ct = CompressorRegistry::instance()
                      .create("coo", {{"keep", "0.5"}})
                      ->compress({t, nullptr, cubemap, grid}, Progress::null());
  ASSERT_TRUE(ct->expected_frobenius_error().has_value());
  const double expected = *ct->expected_frobenius_error();
  EXPECT_GT(expected, 0.05) << "half the entries dropped";
  const FrobeniusError measured = frobenius_error(*ct, t, grid);
  ASSERT_TRUE(measured.exact);
  EXPECT_NEAR(measured.relative, expected, 1e-5 * expected);
  EXPECT_LT(ct->storage().total_bytes(), t.nnz() * 12);
}

bool lists_coo(const std::string& text) {
  const auto json = nlohmann::json::parse(text);
  for (const auto& b : json.at("backends"))
    if (b.at("name") == "coo") return b.at("origin") == "built-in";
  return false;
}

// The CLI built with the test-only backends lists it; the one users run does not.
TEST(CooBackend, IsListedByTheTestCliOnly) {
  testing::TempDir dir("coo_cli");
  const auto test_cli = testing::run_cli("list --json", dir.path(), {}, PRTLAB_TEST_CLI_PATH);
  ASSERT_EQ(test_cli.exit_code, 0) << test_cli.err;
  EXPECT_TRUE(lists_coo(test_cli.out)) << test_cli.out;
  const auto cli = testing::run_cli("list --json", dir.path());
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  EXPECT_FALSE(lists_coo(cli.out)) << cli.out;
}

}  // namespace
}  // namespace prt
