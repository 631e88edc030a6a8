// `prtlab precompute`, `compress`, `relight`, `list` and `devices` on the tiny test scene, run as a
// user would: exit codes, documented JSON keys, the cache, and errors that name the problem.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "prtlab/storage/data_paths.h"
#include "support/cli_runner.h"
#include "support/temp_dir.h"

namespace prt {
namespace {
namespace fs = std::filesystem;
using prt::testing::run_cli;

class BackendCli : public ::testing::Test {
 protected:
  void SetUp() override { env_ = "PRTLAB_CACHE=\"" + (dir_ / "cache").string() + "\" "; }
  prt::testing::CliResult run(const std::string& args) const { return run_cli(args, dir_, env_); }
  nlohmann::json run_json(const std::string& args) const {
    const auto r = run(args);
    EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.err;
    return nlohmann::json::parse(r.out);
  }
  prt::testing::TempDir tmp_{"backend_cli"};
  fs::path dir_ = tmp_.path();
  std::string env_;
};

// PoCL will not start without a writable kernel cache, and the ICD loader then lists no
// platform: an unwritable prtlab cache must move PoCL's cache elsewhere and say so, not make the
// driver look missing. (A path below a regular file is unwritable even for root.)
TEST_F(BackendCli, AnUnwritableCacheDoesNotHideOpenCL) {
  std::ofstream(dir_ / "blocker") << "a file, not a folder";
  const auto r = run_cli(
      "devices --json", dir_,
      "env -u POCL_CACHE_DIR PRTLAB_CACHE=\"" + (dir_ / "blocker" / "cache").string() + "\" ");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_FALSE(j["devices"].empty()) << r.err;
  EXPECT_NE(r.err.find("[cache-not-writable]"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("install pocl"), std::string::npos) << r.err;
}

TEST_F(BackendCli, PrecomputeTwiceIsACacheHit) {
  const auto first = run_json("-q precompute tiny-sphere-plane --json");
  const auto second = run_json("-q precompute tiny-sphere-plane --json");
  EXPECT_FALSE(first["cache_hit"].get<bool>());
  EXPECT_TRUE(second["cache_hit"].get<bool>());
  EXPECT_EQ(first["nnz"], second["nnz"]);
  EXPECT_EQ(first["vertices"].get<int>(), 320);
  EXPECT_EQ(first["columns"].get<int>(), 6 * 8 * 8);
  EXPECT_EQ(first["rows"].get<int>(), 320 * 16);
  EXPECT_DOUBLE_EQ(first["mflops_per_relight"].get<double>(),
                   2.0 * first["nnz"].get<double>() / 1e6);
  EXPECT_TRUE(first.contains("prtlab"));
  const auto forced = run_json("-q precompute tiny-sphere-plane --json --force");
  EXPECT_FALSE(forced["cache_hit"].get<bool>());
}

TEST_F(BackendCli, CompressUncompressedIsExact) {
  const auto j =
      run_json("-q compress tiny-sphere-plane --backend uncompressed --lights 2 --repeat 1 --json");
  EXPECT_LT(j["rel_l2_error_max"].get<double>(), 1e-6);
  EXPECT_EQ(j["errors"].size(), 2u);
  EXPECT_NEAR(j["computation_percent"].get<double>(), 100.0, 1e-9);
  EXPECT_GT(j["storage_bytes"].get<double>(), 0.0);
  EXPECT_EQ(j["parameters"]["seed"], "1");
  if (!j["ms_per_relight_opencl"].is_null()) {
    EXPECT_LT(j["opencl_vs_cpp_rel_l2"].get<double>(), 1e-5);
  }
  // The image comparison renders the exact path against itself.
  EXPECT_EQ(j["image"]["environment"], "courtyard");
  EXPECT_EQ(j["image"]["width"].get<int>(), 256);
  EXPECT_LT(j["image"]["error"]["relative_l2"].get<double>(), 1e-6);
  EXPECT_TRUE(j["paper"].is_array() && j["paper"].empty());
}

// The image error of a lossy backend against the exact image, at the size and environment asked
// for; --no-image skips it.
TEST_F(BackendCli, CompressComparesTheImageWithTheExactOne) {
  const auto j = run_json(
      "-q compress tiny-sphere-plane --backend haar --param k=1 --lights 1 --repeat 1 --json "
      "--image-size 64 48 --image-environment sun:100");
  EXPECT_EQ(j["image"]["width"].get<int>(), 64);
  EXPECT_EQ(j["image"]["height"].get<int>(), 48);
  EXPECT_EQ(j["image"]["environment"], "sun-100");
  const double err = j["image"]["error"]["relative_l2"].get<double>();
  EXPECT_GT(err, 1e-3);
  EXPECT_LT(err, 2.0);
  const auto skipped = run_json(
      "-q compress tiny-sphere-plane --backend haar --param k=1 --lights 1 --repeat 1 "
      "--json --no-image");
  EXPECT_TRUE(skipped["image"].is_null());
  const auto bad = run("-q compress tiny-sphere-plane --backend haar --image-environment nowhere");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("nowhere"), std::string::npos) << bad.err;
}

// A published number is printed where backend, scene and parameters match (numerically: 0.50 is
// 0.5), and only there.
TEST_F(BackendCli, CompressPrintsThePapersNumberBesideOurs) {
  const auto cli = PRTLAB_TEST_CLI_PATH;
  const auto r = run_cli(
      "-q compress tiny-sphere-plane --backend coo --param keep=0.50 --lights 1 --repeat 1 "
      "--no-image",
      dir_, env_, cli);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("paper            half of each row: 1.0 MB (made up)"), std::string::npos)
      << r.out;
  const auto j = nlohmann::json::parse(
      run_cli("-q compress tiny-sphere-plane --backend coo --param keep=0.5 --lights 1 --repeat 1 "
              "--no-image --json",
              dir_, env_, cli)
          .out);
  ASSERT_EQ(j["paper"].size(), 1u);
  EXPECT_EQ(j["paper"][0]["source"], "tests/backends/coo/coo.cpp");
  const auto other = run_cli(
      "-q compress tiny-sphere-plane --backend coo --param keep=0.25 --lights 1 --repeat 1 "
      "--no-image",
      dir_, env_, cli);
  ASSERT_EQ(other.exit_code, 0) << other.err;
  EXPECT_EQ(other.out.find("paper "), std::string::npos) << other.out;
}

TEST_F(BackendCli, RelightWithBackendMatchesExact) {
  if (!fs::exists(data_dir() / "envmaps" / "courtyard.exr"))
    GTEST_SKIP() << "data cache missing (scripts/setup.sh --data)";
  const auto exact = run_json("-q relight tiny-sphere-plane --env courtyard --repeat 1 --json");
  EXPECT_LT(exact["float_vs_double_rel_l2"].get<double>(), 1e-6);
  const auto backend = run_json(
      "-q relight tiny-sphere-plane --env courtyard --repeat 1 --backend uncompressed --json");
  EXPECT_LT(backend["rel_l2_error"].get<double>(), 1e-6);
}

TEST_F(BackendCli, BadBackendOrParameterIsAClearError) {
  auto r = run("compress tiny-sphere-plane --backend no-such-backend");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("unknown backend 'no-such-backend'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("uncompressed"), std::string::npos) << r.err;
  r = run("compress tiny-sphere-plane --backend uncompressed --param bogus=1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("unknown parameter 'bogus'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("seed"), std::string::npos) << r.err;  // lists the valid ones
  // Kernel variants are device options, not parameters (they never enter the cache key).
  r = run("compress tiny-sphere-plane --backend uncompressed --param opencl_kernel=lanes");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("unknown parameter 'opencl_kernel'"), std::string::npos) << r.err;
  r = run("compress tiny-sphere-plane --backend uncompressed --device-param opencl_kernel=bogus");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("opencl_kernel"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("rows"), std::string::npos) << r.err;  // lists the choices
  r = run("compress tiny-sphere-plane --backend uncompressed --param seed=-1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("out of range"), std::string::npos) << r.err;
  r = run("precompute no-such-scene");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no-such-scene"), std::string::npos) << r.err;
}

TEST_F(BackendCli, ListAndDevices) {
  const auto list = run_json("list --json");
  bool found = false;
  for (const auto& b : list["backends"])
    if (b["name"] == "uncompressed") {
      found = true;
      EXPECT_TRUE(b["lossless"].get<bool>());
      EXPECT_EQ(b["origin"], "built-in");
    }
  EXPECT_TRUE(found);
  found = false;
  for (const auto& m : list["materials"])
    if (m["name"] == "full") {
      found = true;
      EXPECT_TRUE(m["lossless"].get<bool>());
      EXPECT_EQ(m["origin"], "built-in");
      EXPECT_TRUE(m["parameters"].is_array());
      EXPECT_TRUE(m["device_parameters"].is_array());
      EXPECT_FALSE(m["description"].get<std::string>().empty());
    }
  EXPECT_TRUE(found) << "the full material is listed";
  for (const auto& b : list["backends"])
    EXPECT_NE(b["name"], "full") << "a material is no transfer backend";
  EXPECT_EQ(list["shared_parameters"][0]["key"], "seed");
  const auto devices = run_json("devices --json");
  ASSERT_TRUE(devices.contains("devices"));
  EXPECT_EQ(devices["selected"].is_null(), devices["devices"].empty());
  const auto strict = run("--device no-such-device --strict-device devices");
  EXPECT_EQ(strict.exit_code, 1);
  EXPECT_NE(strict.err.find("no-such-device"), std::string::npos) << strict.err;
}

// What a harness reads to sweep any backend: inputs, output basis and size knob, per backend.
TEST_F(BackendCli, ListShowsInputsOutputBasisAndSizeKnob) {
  const auto r = run_cli("list --json", dir_, env_, PRTLAB_TEST_CLI_PATH);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto list = nlohmann::json::parse(r.out);
  std::map<std::string, nlohmann::json> by_name;
  for (const auto& b : list["backends"]) by_name[b["name"].get<std::string>()] = b;
  ASSERT_TRUE(by_name.contains("bicluster") && by_name.contains("uncompressed") &&
              by_name.contains("coo") && by_name.contains("sh_probe"))
      << r.out;
  for (const auto& [name, b] : by_name) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(b.contains("inputs") && b.contains("output_basis") && b.contains("size_knob"));
    EXPECT_TRUE(b["inputs"]["sh_order"].is_number_integer());
    EXPECT_TRUE(b["inputs"]["mesh"].is_boolean());
    EXPECT_TRUE(b["inputs"]["btfs"].is_boolean());
    if (!b["size_knob"].is_null()) {
      EXPECT_LT(b["size_knob"]["min"].get<double>(), b["size_knob"]["max"].get<double>());
      bool declared = false;
      for (const auto& p : b["parameters"]) declared |= p["key"] == b["size_knob"]["key"];
      EXPECT_TRUE(declared) << "the knob names one of the backend's parameters";
    }
  }
  EXPECT_TRUE(by_name["uncompressed"]["size_knob"].is_null());
  EXPECT_EQ(by_name["uncompressed"]["output_basis"], "pixel");
  const auto& bicluster = by_name["bicluster"]["size_knob"];
  EXPECT_EQ(bicluster["key"], "error");
  EXPECT_EQ(bicluster["direction"], "larger_is_less_storage");
  EXPECT_EQ(bicluster["scale"], "log");
  EXPECT_EQ(by_name["coo"]["size_knob"]["key"], "keep");
  EXPECT_EQ(by_name["coo"]["size_knob"]["direction"], "larger_is_more_storage");
  EXPECT_EQ(by_name["coo"]["size_knob"]["min"].get<double>(), 0.0) << "the parameter's own range";
  EXPECT_EQ(by_name["coo"]["size_knob"]["max"].get<double>(), 1.0);
  EXPECT_EQ(by_name["sh_probe"]["output_basis"], "sh");
  EXPECT_EQ(by_name["sh_probe"]["size_knob"]["key"], "order");
  EXPECT_EQ(by_name["sh_probe"]["size_knob"]["direction"], "larger_is_more_storage");
}

}  // namespace
}  // namespace prt
