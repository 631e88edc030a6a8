// The out-of-tree plugin path, end to end. examples/plugin-template is a separate CMake project
// that ctest's fixture plugin.template_build configures and builds against this build tree's
// CMake package (tests/plugin/CMakeLists.txt); here it is loaded into the registry, used, saved
// and loaded, and listed by the CLI. Two broken libraries are refused with messages that say
// why. (The conformance suite runs on the template's backend too: ctest's plugin.conformance.)
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "prtlab/base/error.h"
#include "prtlab/btf/btf_generator.h"
#include "prtlab/btf/btf_materials.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/material_error.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/transfer/exact_relight.h"
#include "support/synthetic_cases.h"
#include "support/temp_dir.h"

namespace prt {
namespace {
namespace fs = std::filesystem;
using ::testing::HasSubstr;

const fs::path kTemplatePlugin = PRTLAB_TEMPLATE_PLUGIN;
const fs::path kWrongApiPlugin = PRTLAB_WRONG_API_PLUGIN;
const fs::path kNotAPlugin = PRTLAB_NOT_A_PLUGIN;
const fs::path kMaterialPlugin = PRTLAB_MATERIAL_PLUGIN;

// Before any OpenCL platform query: a private prtlab cache for this process, PoCL's kernel
// cache shared by the test processes of this build (as in the conformance suite).
const fs::path g_scratch = prt::testing::use_private_cache("plugin_test");

/// Loads the template once per process (a second load is an error, tested below).
const std::vector<std::string>& load_template() {
  static const std::vector<std::string> names = load_plugin(kTemplatePlugin);
  return names;
}

class TemplatePlugin : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::exists(kTemplatePlugin))
        << kTemplatePlugin << " is missing: ctest's fixture plugin.template_build builds it "
        << "(ctest -R plugin runs it first)";
    ASSERT_EQ(load_template(), std::vector<std::string>{"quantized8"});
  }

  // A random transfer with counts 1..16 (s = 4), so that 4 or fewer bits must round.
  static const conformance::CaseData& data() {
    static const auto c = conformance::make_case(
        "s4", "random_transfer(seed 5, 40 vertices, S 4, R 4, s 4, density 0.5)",
        conformance::random_transfer(5, 40, 4, 4, 4, 0.5), 4, 4, 5);
    return *c;
  }
  static std::unique_ptr<CompressedTransfer> compress(int bits) {
    const auto compressor =
        CompressorRegistry::instance().create("quantized8", {{"bits", std::to_string(bits)}});
    return compressor->compress(data().input(), Progress::null());
  }
  static LocalRadiance exact(const Cubemap& light) {
    const auto d = relight_exact_double(data().transfer, light.light_vector());
    LocalRadiance out(RadianceBasis::kPixel, data().transfer.local_count(),
                      data().transfer.vertex_count());
    for (std::size_t i = 0; i < d.size(); ++i) out.values[i] = Rgb(d[i]);
    return out;
  }
  static LocalRadiance relight(const CompressedTransfer& ct, const Cubemap& light) {
    LocalRadiance out;
    ct.relight(ct.project_light(light), out);
    return out;
  }
};

TEST_F(TemplatePlugin, RegistersQuantized8WithItsParameterAndOrigin) {
  const CompressorEntry& e = CompressorRegistry::instance().get("quantized8");
  EXPECT_EQ(e.origin, kTemplatePlugin.string());
  EXPECT_FALSE(e.lossless);
  ASSERT_EQ(e.params.size(), 1u);
  EXPECT_EQ(e.params[0].key, "bits");
  EXPECT_EQ(e.params[0].default_value, "8");
  EXPECT_EQ(e.params[0].min, 1.0);
  EXPECT_EQ(e.params[0].max, 8.0);
  // Validation runs in prtlab against the plugin's specs.
  EXPECT_THROW(CompressorRegistry::instance().create("quantized8", {{"bits", "9"}}),
               ParameterError);
}

TEST_F(TemplatePlugin, EightBitsAreExact) {
  const auto ct = compress(8);
  const TransferMatrix& t = data().transfer;
  EXPECT_EQ(ct->backend(), "quantized8");
  EXPECT_EQ(ct->declared_error_bound(), 0.0);
  EXPECT_EQ(ct->flops_per_relight(), 2.0 * static_cast<double>(t.nnz()));
  EXPECT_EQ(ct->storage().total_bytes(), 4 * (t.rows() + 1) + 3 * t.nnz() + 4 * t.rows())
      << "u32 offsets, u16 columns, u8 codes, f32 row steps";
  for (const Cubemap& light : data().lights) {
    const LocalRadiance out = relight(*ct, light), ref = exact(light);
    EXPECT_LE(relative_l2_error(out, ref), 1e-6);
    EXPECT_LE(max_relative_error(out, ref), 1e-6);
  }
}

TEST_F(TemplatePlugin, FewerBitsRoundWithinTheDeclaredBound) {
  const TransferMatrix& t = data().transfer;
  // With counts up to 16 and 15 levels (bits = 4), counts c <= 8 keep their code and are
  // stored as c * 16/15: the bound is exactly 1/15. With 7 levels or fewer, count 1 rounds to
  // code 0 and is dropped: the bound is 1 and there are fewer entries.
  struct Expect {
    int bits;
    double bound;
  };
  for (const auto& [bits, expected_bound] : {Expect{4, 1.0 / 15}, Expect{3, 1.0}, Expect{1, 1.0}}) {
    SCOPED_TRACE(::testing::Message() << "bits = " << bits);
    const auto ct = compress(bits);
    const double bound = ct->declared_error_bound();
    EXPECT_NEAR(bound, expected_bound, 1e-12);
    if (bits < 4) {
      EXPECT_LT(ct->flops_per_relight(), 2.0 * static_cast<double>(t.nnz()));
    } else {
      EXPECT_EQ(ct->flops_per_relight(), 2.0 * static_cast<double>(t.nnz()));
    }
    for (const Cubemap& light : data().lights) {
      const LocalRadiance out = relight(*ct, light), ref = exact(light);
      const double error = relative_l2_error(out, ref);
      EXPECT_GT(error, 1e-4) << "rounding was expected";
      EXPECT_LE(error, bound * (1 + 1e-6) + 1e-6);
    }
  }
}

TEST_F(TemplatePlugin, OpenClMatchesTheCppRelight) {
  ClContext* ctx = default_context();
  if (ctx == nullptr) GTEST_SKIP() << "no OpenCL device on this machine";
  for (int bits : {8, 2}) {
    SCOPED_TRACE(::testing::Message() << "bits = " << bits << " on " << ctx->info().label());
    const auto ct = compress(bits);
    const auto device = upload_compressed(*ct, *ctx);
    ASSERT_NE(device, nullptr);
    for (const Cubemap& light : data().lights) {
      const LightCoeffs coeffs = ct->project_light(light);
      LocalRadiance cpp, gpu;
      ct->relight(coeffs, cpp);
      EXPECT_GE(device->relight(coeffs, gpu), 0.0);
      EXPECT_LE(max_relative_error(gpu, cpp), 1e-5);
    }
  }
}

TEST_F(TemplatePlugin, SavedFilesLoadThroughTheRegistry) {
  const auto ct = compress(2);
  const fs::path file = g_scratch / "quantized8.prt";
  save_compressed(*ct, file);
  const auto loaded = load_compressed(file);
  EXPECT_EQ(loaded->backend(), "quantized8");
  EXPECT_EQ(loaded->declared_error_bound(), ct->declared_error_bound());
  EXPECT_EQ(loaded->storage().total_bytes(), ct->storage().total_bytes());
  const LocalRadiance a = relight(*ct, data().lights[1]), b = relight(*loaded, data().lights[1]);
  ASSERT_EQ(a.values.size(), b.values.size());
  EXPECT_EQ(std::memcmp(a.values.data(), b.values.data(), a.values.size() * sizeof(Rgb)), 0);
}

TEST_F(TemplatePlugin, LoadingItAgainIsRefused) {
  const auto before = CompressorRegistry::instance().names();
  try {
    load_plugin(kTemplatePlugin);
    FAIL() << "a second load registered quantized8 twice";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("already loaded"));
  }
  EXPECT_EQ(CompressorRegistry::instance().names(), before);
}

TEST(PluginRefusal, AnotherApiVersionIsRefusedWithAClearMessage) {
  ASSERT_TRUE(fs::exists(kWrongApiPlugin)) << kWrongApiPlugin;
  const auto before = CompressorRegistry::instance().names();
  try {
    load_plugin(kWrongApiPlugin);  // its registration function would abort()
    FAIL() << "a plugin built for another API version was loaded";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr(kWrongApiPlugin.string()));
    EXPECT_THAT(e.what(), HasSubstr(fmt::format(
                              "plugin API version {} does not match this prtlab's version {}",
                              kPluginApiVersion + 1, kPluginApiVersion)));
    EXPECT_THAT(e.what(), HasSubstr("rebuild the plugin"));
  }
  EXPECT_EQ(CompressorRegistry::instance().names(), before);
}

// A plugin that registers a material (tests/plugin/material_plugin.cpp): it lands in the material
// registry with its origin, compresses, saves and loads through the registry, and loading it
// again is refused. The material conformance suite runs on it as plugin.material_conformance.
TEST(MaterialPlugin, RegistersItsMaterialWithItsOriginAndWorks) {
  ASSERT_TRUE(fs::exists(kMaterialPlugin)) << kMaterialPlugin;
  EXPECT_FALSE(MaterialRegistry::instance().contains("u8_vectors"));
  EXPECT_EQ(load_plugin(kMaterialPlugin), std::vector<std::string>{"u8_vectors"});
  ASSERT_TRUE(MaterialRegistry::instance().contains("u8_vectors"));
  EXPECT_EQ(MaterialRegistry::instance().get("u8_vectors").origin, kMaterialPlugin.string());
  EXPECT_FALSE(CompressorRegistry::instance().contains("u8_vectors"));

  BtfParams p;
  p.resolution = 4;
  p.view_side = 3;
  p.light_side = 3;
  p.supersampling = 1;
  p.geometry_grid = 32;
  const auto btf = std::make_shared<const Btf>(generate_btf(make_btf_material("checker", 32), p));
  const auto m = compress_material("u8_vectors", {}, btf);
  const double error = material_error(*m, *btf).relative_l2;
  EXPECT_GT(error, 0.0) << "u8 codes round";
  EXPECT_LE(error, m->declared_error_bound());
  const fs::path file = g_scratch / "u8.prt";
  save_material(*m, file);
  EXPECT_EQ(load_material(file)->declared_error_bound(), m->declared_error_bound());
  try {
    load_plugin(kMaterialPlugin);
    FAIL() << "the same plugin was loaded twice";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("already loaded"));
  }
}

TEST(PluginRefusal, ALibraryThatRegistersNothingIsNotAPlugin) {
  ASSERT_TRUE(fs::exists(kNotAPlugin)) << kNotAPlugin;
  try {
    load_plugin(kNotAPlugin);
    FAIL() << "a library without entry points was accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("not a prtlab plugin"));
    EXPECT_THAT(e.what(), HasSubstr("PRT_REGISTER_COMPRESSOR"));
  }
}

TEST(PluginRefusal, AMissingFileIsNamed) {
  const fs::path missing = g_scratch / "no_such_plugin.so";
  try {
    load_plugin(missing);
    FAIL() << "a missing plugin file was accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr(missing.string()));
    EXPECT_THAT(e.what(), HasSubstr("not found"));
  }
}

// ---- the CLI's --plugin ----

struct RunResult {
  int exit_code = -1;
  std::string out, err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

RunResult run_cli(const std::string& args) {
  const fs::path out = g_scratch / "stdout.txt", err = g_scratch / "stderr.txt";
  const std::string cmd = std::string("\"") + PRTLAB_CLI_PATH + "\" " + args + " >\"" +
                          out.string() + "\" 2>\"" + err.string() + "\"";
  const int status = std::system(cmd.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

const nlohmann::json* find_backend(const nlohmann::json& list, const std::string& name) {
  for (const auto& b : list.at("backends"))
    if (b.at("name") == name) return &b;
  return nullptr;
}

TEST(PluginCli, ListShowsThePluginBackendWhereverTheOptionStands) {
  ASSERT_TRUE(fs::exists(kTemplatePlugin))
      << kTemplatePlugin << " is built by ctest's plugin.template_build";
  const std::string plugin = "\"" + kTemplatePlugin.string() + "\"";
  for (const std::string& args :
       {"list --json --plugin " + plugin, "--plugin " + plugin + " list --json"}) {
    SCOPED_TRACE("prtlab " + args);
    const RunResult r = run_cli(args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto list = nlohmann::json::parse(r.out);
    const nlohmann::json* q8 = find_backend(list, "quantized8");
    ASSERT_NE(q8, nullptr) << r.out;
    EXPECT_EQ(q8->at("origin"), kTemplatePlugin.string());
    ASSERT_EQ(q8->at("parameters").size(), 1u);
    EXPECT_EQ(q8->at("parameters")[0].at("key"), "bits");
    EXPECT_NE(find_backend(list, "uncompressed"), nullptr) << "built-in backends stay listed";
  }
  const RunResult without = run_cli("list --json");
  ASSERT_EQ(without.exit_code, 0) << without.err;
  EXPECT_EQ(find_backend(nlohmann::json::parse(without.out), "quantized8"), nullptr);
}

// dlopen() reads a name without a slash as a library to search for on the library path; prtlab
// reads it as every other file argument, relative to the working directory.
TEST(PluginCli, ABareFileNameIsTheFileInTheWorkingDirectory) {
  ASSERT_TRUE(fs::exists(kTemplatePlugin)) << kTemplatePlugin;
  const fs::path dir = g_scratch / "bare-name";
  fs::create_directories(dir);
  fs::copy_file(kTemplatePlugin, dir / "q8.so", fs::copy_options::overwrite_existing);
  const fs::path out = g_scratch / "stdout.txt", err = g_scratch / "stderr.txt";
  const std::string cmd = "cd \"" + dir.string() + "\" && \"" + PRTLAB_CLI_PATH +
                          "\" list --json --plugin q8.so >\"" + out.string() + "\" 2>\"" +
                          err.string() + "\"";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << slurp(err);
  EXPECT_NE(find_backend(nlohmann::json::parse(slurp(out)), "quantized8"), nullptr);
}

TEST(PluginCli, AMismatchedPluginStopsTheCommandWithTheReason) {
  ASSERT_TRUE(fs::exists(kWrongApiPlugin)) << kWrongApiPlugin;
  const RunResult r = run_cli("list --plugin \"" + kWrongApiPlugin.string() + "\"");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("plugin API version"));
  EXPECT_THAT(r.err, HasSubstr(kWrongApiPlugin.string()));
  EXPECT_EQ(r.out, "") << "nothing is listed when a plugin fails to load";
}

}  // namespace
}  // namespace prt
