// The OpenCL runtime: embedded kernels, device selection, program build and caches, padded
// launches, timing and error messages. Tests that need a device skip (with a message) when
// the machine has no OpenCL platform; the selection rules are tested on synthetic device
// lists and run everywhere.
#include "prtlab/opencl/cl_runtime.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <sstream>
#include <vector>

#include "prtlab/base/log.h"
#include "support/temp_dir.h"

namespace prt {
namespace {
namespace fs = std::filesystem;

// Before main, so before any platform query: a private program cache per test process (the
// disk-cache tests corrupt and count files), and PoCL's own kernel cache shared by the test
// processes of this build directory, so LLVM compiles the self-test kernels once per build
// rather than once per test (ctest runs every test in its own process).
const fs::path g_cache_root = [] {
  const fs::path root = prt::testing::use_private_cache("cl_test");
  ::unsetenv("PRTLAB_OPENCL_CACHE");
  return root;
}();

ClContext* test_context() {
  return default_context();
}

#define PRT_REQUIRE_OPENCL()                                                               \
  do {                                                                                     \
    if (test_context() == nullptr)                                                         \
      GTEST_SKIP() << "no OpenCL platform on this machine (install pocl-opencl-icd); the " \
                      "C++ reference paths are tested elsewhere";                          \
  } while (0)

// |actual - expected| <= tol * |expected|, printing the relative error on failure.
::testing::AssertionResult near_relative(double actual, double expected, double tol) {
  const double err = std::abs(actual - expected) / std::max(std::abs(expected), 1e-30);
  if (err <= tol) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "actual " << actual << " vs expected " << expected
                                       << ": relative error " << err << " > " << tol;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// ---- embedded kernel sources (no device needed) ----

// Core's kernels/*.cl and every backend folder's *.cl (built-in and test-only: this binary
// links both) are registered under their names with their exact bytes.
TEST(KernelSources, EveryKernelFileIsEmbeddedByteForByte) {
  const fs::path source = PRTLAB_SOURCE_DIR;
  std::map<std::string, fs::path> on_disk;
  auto scan = [&](const fs::path& dir) {
    for (const auto& e : fs::directory_iterator(dir))
      if (e.is_regular_file() && e.path().extension() == ".cl")
        on_disk[e.path().stem().string()] = e.path();
  };
  scan(source / "kernels");
  for (const char* root : {"compressors", "tests/backends"})
    for (const auto& backend : fs::directory_iterator(source / root))
      if (backend.is_directory()) scan(backend.path());
  std::vector<std::string> names;
  for (const auto& [name, path] : on_disk) names.push_back(name);
  EXPECT_EQ(kernel_names(), names) << "rebuild: the embedded table is stale";
  for (const auto& [name, path] : on_disk) {
    EXPECT_EQ(kernel_source(name), read_text(path)) << name;
    EXPECT_EQ(kernel_source(name + ".cl"), kernel_source(name));
  }
  EXPECT_NE(kernel_source("selftest").find("reduce_sum"), std::string_view::npos);
}

TEST(KernelSources, UnknownNameListsTheKnownNames) {
  try {
    (void)kernel_source("no_such_backend");
    FAIL() << "expected prt::Error";
  } catch (const Error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("no_such_backend"), std::string::npos) << msg;
    EXPECT_NE(msg.find("selftest"), std::string::npos) << msg;
    EXPECT_NE(msg.find("prelude"), std::string::npos) << msg;
  }
  EXPECT_FALSE(has_kernel_source("no_such_backend"));
  EXPECT_TRUE(has_kernel_source("selftest"));
}

TEST(KernelDefines, FormatsReplacesAndValidates) {
  KernelDefines d;
  d.set("PRT_WG_SIZE", 128).set("SCALE", 0.5f).set("FLAG").set("PRT_WG_SIZE", 32);
  EXPECT_EQ(d.text(), "#define PRT_WG_SIZE 32\n#define SCALE 0.500000000f\n#define FLAG 1\n");
  EXPECT_EQ(KernelDefines().set("ONE", 1.0f).entries().front().second, "1.00000000f");
  EXPECT_THROW(d.set("2BAD", 1), ParameterError);
  EXPECT_THROW(d.set("BAD NAME", 1), ParameterError);
  const std::string src = assemble_program_source("x.cl", "KERNEL_TEXT", d);
  // Defines come before the prelude, which comes before the kernel, each behind a #line.
  const auto def = src.find("#define PRT_WG_SIZE 32");
  const auto prelude = src.find("#line 1 \"prelude.cl\"");
  const auto body = src.find("#line 1 \"x.cl\"\nKERNEL_TEXT");
  ASSERT_NE(def, std::string::npos);
  ASSERT_NE(prelude, std::string::npos);
  ASSERT_NE(body, std::string::npos);
  EXPECT_LT(def, prelude);
  EXPECT_LT(prelude, body);
}

// ---- device selection rules on synthetic lists (no device needed) ----

std::vector<DeviceInfo> fake_devices(bool with_gpu) {
  DeviceInfo pocl;
  pocl.platform_index = 0;
  pocl.device_index = 0;
  pocl.platform_name = "Portable Computing Language";
  pocl.platform_vendor = "The pocl project";
  pocl.device_name = "pthread-haswell-AMD EPYC 7B13";
  pocl.is_cpu = true;
  DeviceInfo intel;
  intel.platform_index = 1;
  intel.device_index = 0;
  intel.platform_name = "Intel(R) OpenCL";
  intel.device_name = "Intel(R) Xeon(R) CPU";
  intel.is_cpu = true;
  DeviceInfo gpu;
  gpu.platform_index = 2;
  gpu.device_index = 1;
  gpu.platform_name = "NVIDIA CUDA";
  gpu.vendor = "NVIDIA Corporation";
  gpu.device_name = "NVIDIA H100 80GB HBM3";
  gpu.is_gpu = true;
  std::vector<DeviceInfo> out = {intel, pocl};
  if (with_gpu) out.push_back(gpu);
  return out;
}

TEST(DeviceChoice, DefaultIsFirstGpuThenPoclThenFirst) {
  const auto with_gpu = fake_devices(true);
  EXPECT_EQ(choose_device(with_gpu, {}), 2u);
  EXPECT_EQ(choose_device(with_gpu, {"auto", true}), 2u);
  const auto cpus = fake_devices(false);
  EXPECT_EQ(choose_device(cpus, {}), 1u) << "PoCL's CPU device before another CPU runtime";
  std::vector<DeviceInfo> other = {cpus[0]};
  EXPECT_EQ(choose_device(other, {}), 0u);
}

TEST(DeviceChoice, StringsMatchTypeIndexAndNames) {
  const auto d = fake_devices(true);
  EXPECT_EQ(choose_device(d, {"gpu", true}), 2u);
  EXPECT_EQ(choose_device(d, {"cpu", true}), 0u);
  EXPECT_EQ(choose_device(d, {"pocl", true}), 1u);
  EXPECT_EQ(choose_device(d, {"POCL", true}), 1u);
  EXPECT_EQ(choose_device(d, {"nvidia", true}), 2u);
  EXPECT_EQ(choose_device(d, {"epyc", true}), 1u);
  EXPECT_EQ(choose_device(d, {"2:1", true}), 2u);
  EXPECT_EQ(choose_device(d, {"0:0", true}), 1u);
  EXPECT_THROW(choose_device(d, {"2:0", true}), ParameterError);
}

TEST(DeviceChoice, NonsenseIsAnErrorWhenStrictAndAWarnedFallbackOtherwise) {
  const auto d = fake_devices(true);
  try {
    (void)choose_device(d, {"quantum-abacus", true});
    FAIL() << "expected ParameterError";
  } catch (const ParameterError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("quantum-abacus"), std::string::npos) << msg;
    EXPECT_NE(msg.find("NVIDIA H100"), std::string::npos) << "lists the devices: " << msg;
  }
  const int warnings = warning_count();
  EXPECT_EQ(choose_device(d, {"quantum-abacus", false}), 2u);
  EXPECT_EQ(warning_count(), warnings + 1);
}

TEST(DeviceChoice, NoDeviceIsNulloptUnlessStrict) {
  EXPECT_EQ(choose_device({}, {}), std::nullopt);
  EXPECT_EQ(choose_device({}, {"gpu", false}), std::nullopt);
  EXPECT_THROW(choose_device({}, {"", true}), ParameterError);
}

// Sets an environment variable for one scope and restores the previous value (the user's
// PRTLAB_DEVICE must still apply to the tests that run after this one).
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value) {
      ::setenv(name, value, 1);
    } else {
      ::unsetenv(name);
    }
  }
  ~ScopedEnv() {
    if (old_) {
      ::setenv(name_, old_->c_str(), 1);
    } else {
      ::unsetenv(name_);
    }
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

TEST(DeviceRequest, CliOverridesEnvironment) {
  {
    ScopedEnv device("PRTLAB_DEVICE", "pocl");
    ScopedEnv strict("PRTLAB_DEVICE_STRICT", "1");
    const DeviceRequest from_env = DeviceRequest::resolve();
    EXPECT_EQ(from_env.spec, "pocl");
    EXPECT_TRUE(from_env.strict);
    EXPECT_EQ(DeviceRequest::resolve("gpu").spec, "gpu");
  }
  ScopedEnv device("PRTLAB_DEVICE", nullptr);
  ScopedEnv strict("PRTLAB_DEVICE_STRICT", "0");
  EXPECT_EQ(DeviceRequest::resolve().spec, "");
  EXPECT_FALSE(DeviceRequest::resolve().strict);
  EXPECT_TRUE(DeviceRequest::resolve("", true).strict);
}

// Without any OpenCL platform, selection warns once per process and returns nullopt. Runs in a
// fresh child process whose ICD loader sees an empty vendor directory.
TEST(DeviceSelection, NoPlatformWarnsOnceAndReturnsNothing) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const fs::path empty = g_cache_root / "no_icd_vendors";
  fs::create_directories(empty);
  EXPECT_EXIT(
      {
        ::setenv("OCL_ICD_VENDORS", empty.c_str(), 1);
        set_log_level(LogLevel::kWarn);
        const int before = warning_count();
        const bool none1 = !select_device(DeviceRequest{}).has_value();
        const bool none2 = !select_device(DeviceRequest{"gpu", false}).has_value();
        const bool ctx_none = !ClContext::open(DeviceRequest{}).has_value();
        bool strict_throws = false;
        try {
          (void)select_device(DeviceRequest{"", true});
        } catch (const ParameterError&) {
          strict_throws = true;
        }
        std::_Exit(
            none1 && none2 && ctx_none && strict_throws && warning_count() == before + 1 ? 0 : 1);
      },
      ::testing::ExitedWithCode(0), "no OpenCL platform");
}

// ---- on the chosen device ----

TEST(ClDevice, InfoDescribesTheDevice) {
  PRT_REQUIRE_OPENCL();
  const DeviceInfo& info = test_context()->info();
  std::printf("device: %s, driver %s, %u compute units, %.0f MB\n", info.label().c_str(),
              info.driver_version.c_str(), info.compute_units, info.global_mem_bytes / 1e6);
  EXPECT_FALSE(info.device_name.empty());
  EXPECT_FALSE(info.platform_name.empty());
  EXPECT_FALSE(info.driver_version.empty());
  EXPECT_NE(info.opencl_version.find("OpenCL"), std::string::npos);
  EXPECT_GT(info.compute_units, 0u);
  EXPECT_GT(info.global_mem_bytes, info.max_alloc_bytes / 2);
  EXPECT_GE(info.max_work_group_size, kDefaultWorkGroupSize);
  nlohmann::json j = info;
  EXPECT_EQ(j.at("device_name"), info.device_name);
  EXPECT_EQ(j.at("driver_version"), info.driver_version);
}

TEST(ClDevice, SelectionByStringOnThisMachine) {
  PRT_REQUIRE_OPENCL();
  const auto devices = list_devices();
  ASSERT_FALSE(devices.empty());
  const auto first_cpu =
      std::find_if(devices.begin(), devices.end(), [](const ClDevice& d) { return d.info.is_cpu; });
  if (first_cpu != devices.end()) {
    const auto cpu = select_device({"cpu", true});
    ASSERT_TRUE(cpu.has_value());
    EXPECT_TRUE(cpu->info.is_cpu);
    EXPECT_EQ(cpu->info.label(), first_cpu->info.label());
    if (first_cpu->info.is_pocl()) {
      EXPECT_TRUE(select_device({"pocl", true})->info.is_pocl());
    }
  }
  const auto by_index = select_device(
      {fmt::format("{}:{}", devices.back().info.platform_index, devices.back().info.device_index),
       true});
  ASSERT_TRUE(by_index.has_value());
  EXPECT_EQ(by_index->info.label(), devices.back().info.label());

  EXPECT_THROW(select_device({"quantum-abacus", true}), ParameterError);
  const int warnings = warning_count();
  const auto fallback = select_device({"quantum-abacus", false});
  ASSERT_TRUE(fallback.has_value());
  EXPECT_EQ(warning_count(), warnings + 1);
  EXPECT_EQ(fallback->info.label(), select_device({"", false})->info.label());
}

constexpr std::uint32_t kPrimeN = 1009;  // not a multiple of any work-group size

TEST(SelfTest, Saxpy4MatchesReferenceAtPrimeSizeAndLeavesPaddingAlone) {
  PRT_REQUIRE_OPENCL();
  ClContext& ctx = *test_context();
  const cl::Program program = build_program(ctx, "selftest");
  cl::Kernel kernel = make_kernel(program, "saxpy4");

  std::mt19937 rng(20240601);
  std::uniform_real_distribution<float> dist(-10.0f, 10.0f);
  const float a = 0.75f;
  constexpr std::size_t kSentinels = 2 * kDefaultWorkGroupSize;
  constexpr float kSentinel = -12345.0f;
  std::vector<cl_float4> x(kPrimeN), y(kPrimeN + kSentinels);
  for (auto& v : x) v = {{dist(rng), dist(rng), dist(rng), 0.0f}};
  for (std::size_t i = 0; i < y.size(); ++i)
    y[i] = i < kPrimeN ? cl_float4{{dist(rng), dist(rng), dist(rng), 0.0f}}
                       : cl_float4{{kSentinel, kSentinel, kSentinel, kSentinel}};

  cl::Buffer bx = upload(ctx, std::span<const cl_float4>(x), "selftest x");
  cl::Buffer by = upload(ctx, std::span<const cl_float4>(y), "selftest y", CL_MEM_READ_WRITE);
  set_args(kernel, kPrimeN, a, bx, by);
  const LaunchRange range = LaunchRange::linear(kPrimeN);
  EXPECT_EQ(range.global[0], 1024u);
  launch(ctx, "selftest.saxpy4", kernel, range);
  std::vector<cl_float4> out(y.size());
  download(ctx, by, std::span<cl_float4>(out), "selftest y");

  for (std::size_t i = 0; i < kPrimeN; ++i)
    for (int c = 0; c < 3; ++c) {
      // Relative to the size of the terms, not of the result: where a*x and y nearly cancel,
      // float rounding of a*x (a device without fused multiply-add) is legitimately large
      // relative to the result.
      const double ax = static_cast<double>(a) * x[i].s[c];
      const double ref = ax + y[i].s[c];
      ASSERT_LE(std::abs(out[i].s[c] - ref), 1e-6 * (std::abs(ax) + std::abs(y[i].s[c])))
          << "element " << i << " channel " << c << ": got " << out[i].s[c] << ", expected " << ref;
    }
  for (std::size_t i = kPrimeN; i < out.size(); ++i)
    ASSERT_EQ(out[i].s[0], kSentinel) << "padded work-item " << i << " wrote past n";
}

TEST(SelfTest, WorkGroupReductionAtPrimeSize) {
  PRT_REQUIRE_OPENCL();
  ClContext& ctx = *test_context();
  cl::Kernel kernel = make_kernel(build_program(ctx, "selftest"), "reduce_sum");
  // Multiples of 1/8 below 2^7: every partial sum is exact in float, so the comparison with
  // the double reference is exact whatever the summation order.
  std::vector<float> x(kPrimeN);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = static_cast<float>((i * 37) % 101) / 8.0f;
  const LaunchRange range = LaunchRange::linear(kPrimeN);
  cl::Buffer bx = upload(ctx, std::span<const float>(x), "reduction input");
  cl::Buffer bp = make_buffer(ctx, range.groups() * sizeof(float), CL_MEM_WRITE_ONLY, "partials");
  set_args(kernel, kPrimeN, bx, bp);
  launch(ctx, "selftest.reduce_sum", kernel, range);
  std::vector<float> partial(range.groups());
  download(ctx, bp, std::span<float>(partial), "partials");
  double total = 0.0;
  for (std::size_t g = 0; g < partial.size(); ++g) {
    double ref = 0.0;
    for (std::size_t i = g * range.local[0];
         i < std::min<std::size_t>(x.size(), (g + 1) * range.local[0]); ++i)
      ref += x[i];
    EXPECT_TRUE(near_relative(partial[g], ref, 1e-6)) << "group " << g;
    total += partial[g];
  }
  double ref_total = 0.0;
  for (float v : x) ref_total += v;
  EXPECT_TRUE(near_relative(total, ref_total, 1e-6));
}

TEST(SelfTest, LaunchWithAWorkGroupTheKernelForbidsNamesTheKernel) {
  PRT_REQUIRE_OPENCL();
  ClContext& ctx = *test_context();
  cl::Kernel kernel = make_kernel(build_program(ctx, "selftest"), "reduce_sum");
  cl::Buffer bx = make_buffer(ctx, 64 * sizeof(float), CL_MEM_READ_ONLY, "x");
  cl::Buffer bp = make_buffer(ctx, 64 * sizeof(float), CL_MEM_WRITE_ONLY, "partials");
  set_args(kernel, 64u, bx, bp);
  try {
    launch(ctx, "", kernel, LaunchRange::linear(64, kDefaultWorkGroupSize / 2));
    ctx.finish();
    FAIL() << "reduce_sum requires work-groups of PRT_WG_SIZE";
  } catch (const ClError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("reduce_sum"), std::string::npos) << msg;
    EXPECT_NE(msg.find(ctx.info().device_name), std::string::npos) << msg;
    EXPECT_NE(msg.find("work-group 32x1"), std::string::npos) << msg;
    EXPECT_EQ(e.code(), CL_INVALID_WORK_GROUP_SIZE);
  }
}

TEST(ProgramCache, SecondBuildIsTheCachedProgram) {
  PRT_REQUIRE_OPENCL();
  ClContext& ctx = *test_context();
  const cl::Program first = build_program(ctx, "selftest");
  const ProgramCacheStats before = ctx.programs().stats();
  const cl::Program second = build_program(ctx, "selftest");
  const ProgramCacheStats after = ctx.programs().stats();
  EXPECT_EQ(first(), second()) << "the same cl_program handle";
  EXPECT_EQ(after.memory_hits, before.memory_hits + 1);
  EXPECT_EQ(after.source_builds, before.source_builds);
  EXPECT_EQ(after.binary_loads, before.binary_loads);
  // Different defines are a different program.
  const cl::Program other = build_program(ctx, "selftest", KernelDefines().set("PRT_UNUSED", 1));
  EXPECT_NE(other(), first());
}

// The path of the disk binary of the default self-test program.
fs::path selftest_binary(ClContext& ctx) {
  const std::string src = assemble_program_source("selftest.cl", kernel_source("selftest"), {});
  return ctx.programs().disk_path(ctx.programs().key(src, ""));
}

void expect_saxpy_works(ClContext& ctx, const cl::Program& program) {
  cl::Kernel k = make_kernel(program, "saxpy4");
  std::vector<cl_float4> x(5, cl_float4{{1, 2, 3, 0}}), y(5, cl_float4{{10, 20, 30, 0}});
  cl::Buffer bx = upload(ctx, std::span<const cl_float4>(x), "x");
  cl::Buffer by = upload(ctx, std::span<const cl_float4>(y), "y", CL_MEM_READ_WRITE);
  set_args(k, 5u, 2.0f, bx, by);
  launch(ctx, "selftest.saxpy4", k, LaunchRange::linear(5));
  download(ctx, by, std::span<cl_float4>(y), "y");
  EXPECT_EQ(y[4].s[0], 12.0f);
  EXPECT_EQ(y[4].s[2], 36.0f);
}

TEST(ProgramCache, NewProcessLoadsTheDiskBinary) {
  PRT_REQUIRE_OPENCL();
  ClContext& ctx = *test_context();
  (void)build_program(ctx, "selftest");
  const fs::path file = selftest_binary(ctx);
  ASSERT_TRUE(fs::exists(file)) << file;
  EXPECT_EQ(file.parent_path(), g_cache_root / "opencl");
  ctx.programs().clear_memory();  // as if this were a new process
  const ProgramCacheStats before = ctx.programs().stats();
  const cl::Program program = build_program(ctx, "selftest");
  const ProgramCacheStats after = ctx.programs().stats();
  EXPECT_EQ(after.binary_loads, before.binary_loads + 1);
  EXPECT_EQ(after.source_builds, before.source_builds);
  expect_saxpy_works(ctx, program);
}

TEST(ProgramCache, CorruptBinaryFallsBackToSource) {
  PRT_REQUIRE_OPENCL();
  ClContext& ctx = *test_context();
  (void)build_program(ctx, "selftest");
  const fs::path file = selftest_binary(ctx);
  ASSERT_TRUE(fs::exists(file));
  {
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(fs::file_size(file) / 2));
    f.write("garbage!", 8);
  }
  ctx.programs().clear_memory();
  const ProgramCacheStats before = ctx.programs().stats();
  const int warnings = warning_count();
  const cl::Program program = build_program(ctx, "selftest");
  const ProgramCacheStats after = ctx.programs().stats();
  EXPECT_EQ(after.binaries_rejected, before.binaries_rejected + 1);
  EXPECT_EQ(after.source_builds, before.source_builds + 1);
  EXPECT_EQ(warning_count(), warnings + 1);
  expect_saxpy_works(ctx, program);
  // The rebuilt program replaced the bad file.
  ctx.programs().clear_memory();
  (void)build_program(ctx, "selftest");
  EXPECT_EQ(ctx.programs().stats().binary_loads, after.binary_loads + 1);
}

TEST(ProgramCache, TruncatedBinaryFallsBackToSource) {
  PRT_REQUIRE_OPENCL();
  ClContext& ctx = *test_context();
  (void)build_program(ctx, "selftest");
  const fs::path file = selftest_binary(ctx);
  ASSERT_TRUE(fs::exists(file));
  fs::resize_file(file, 20);
  ctx.programs().clear_memory();
  const ProgramCacheStats before = ctx.programs().stats();
  expect_saxpy_works(ctx, build_program(ctx, "selftest"));
  EXPECT_EQ(ctx.programs().stats().binaries_rejected, before.binaries_rejected + 1);
}

TEST(ProgramBuild, SyntaxErrorThrowsWithLogDeviceAndOptions) {
  PRT_REQUIRE_OPENCL();
  ClContext& ctx = *test_context();
  const std::string source =
      "__kernel void broken(__global float* x) {\n"
      "  x[get_global_id(0)] = undeclared_prtlab_identifier * 2.0f;\n"
      "}\n";
  try {
    (void)build_program_source(ctx, "broken.cl", source, {}, "-DPRT_OPTION_MARKER=1");
    FAIL() << "expected ClBuildError";
  } catch (const ClBuildError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("undeclared_prtlab_identifier"), std::string::npos) << msg;
    EXPECT_NE(msg.find(ctx.info().device_name), std::string::npos) << msg;
    EXPECT_NE(msg.find("-DPRT_OPTION_MARKER=1"), std::string::npos) << msg;
    EXPECT_NE(msg.find("broken.cl"), std::string::npos) << msg;
    EXPECT_NE(e.build_log().find("undeclared_prtlab_identifier"), std::string::npos);
    EXPECT_EQ(e.code(), CL_BUILD_PROGRAM_FAILURE);
  }
}

TEST(ProgramBuild, UnknownKernelNameInAProgramListsItsKernels) {
  PRT_REQUIRE_OPENCL();
  try {
    (void)make_kernel(build_program(*test_context(), "selftest"), "saxpy");
    FAIL() << "expected ClError";
  } catch (const ClError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("saxpy4"), std::string::npos) << msg;
    EXPECT_NE(msg.find("reduce_sum"), std::string::npos) << msg;
  }
}

TEST(KernelTimer, LaunchesAreCountedAndSummarised) {
  PRT_REQUIRE_OPENCL();
  ClContext& ctx = *test_context();
  cl::Kernel k = make_kernel(build_program(ctx, "selftest"), "saxpy4");
  std::vector<cl_float4> x(100, cl_float4{{1, 1, 1, 0}});
  cl::Buffer bx = upload(ctx, std::span<const cl_float4>(x), "x");
  cl::Buffer by = upload(ctx, std::span<const cl_float4>(x), "y", CL_MEM_READ_WRITE);
  set_args(k, 100u, 1.0f, bx, by);
  const std::uint64_t before = ctx.timer().count("timer.saxpy4");
  const std::uint64_t unnamed_before = ctx.timer().count("saxpy4");
  for (int i = 0; i < 3; ++i) launch(ctx, "timer.saxpy4", k, LaunchRange::linear(100));
  launch(ctx, "", k, LaunchRange::linear(0));  // empty: counted, nothing runs
  EXPECT_EQ(ctx.timer().count("timer.saxpy4"), before + 3);
  EXPECT_EQ(ctx.timer().count("saxpy4"), unnamed_before + 1)
      << "unnamed launches use the kernel's name";
  const auto stats = ctx.timer().stats("timer.saxpy4");
  ASSERT_TRUE(stats.has_value());
  EXPECT_EQ(stats->count, before + 3);
  EXPECT_GE(stats->total_ms, 0.0);
  const std::string table = ctx.timer().summary();
  EXPECT_NE(table.find("timer.saxpy4"), std::string::npos) << table;
  EXPECT_NE(table.find("launches"), std::string::npos) << table;
}

TEST(Buffers, OversizedAllocationNamesDeviceSizeAndPurpose) {
  PRT_REQUIRE_OPENCL();
  ClContext& ctx = *test_context();
  const std::uint64_t bytes = ctx.info().max_alloc_bytes + (1u << 20);
  try {
    (void)make_buffer(ctx, bytes, CL_MEM_READ_ONLY, "the transfer matrix");
    FAIL() << "expected DeviceOutOfMemory";
  } catch (const DeviceOutOfMemory& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("OpenCL device " + ctx.info().device_name + ": out of memory allocating"),
              std::string::npos)
        << msg;
    EXPECT_NE(msg.find(fmt::format("{:.1f} MB for the transfer matrix", bytes / 1e6)),
              std::string::npos)
        << msg;
  }
  // Empty arrays still give a valid kernel argument.
  EXPECT_NO_THROW((void)upload(ctx, std::span<const float>(), "empty"));
}

}  // namespace
}  // namespace prt
