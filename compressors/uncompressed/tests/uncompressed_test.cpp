// Backend `uncompressed`, beyond the conformance suite: its exact byte accounting, the FLOP
// count of the papers, the light in the pixel basis, parameter checks the ParamSpec ranges
// cannot express, the kernel choice per device type, and refusal of inconsistent files.
#include "uncompressed/uncompressed.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "prtlab/base/error.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/opencl/cl_device.h"
#include "prtlab/storage/archive.h"
#include "prtlab/transfer/exact_relight.h"

namespace prt::uncompressed {
namespace {
namespace fs = std::filesystem;

// 3 vertices, M = 4, N = 24 (R = 2), s = 3; vertex 1 is empty.
TransferMatrix small_transfer() {
  std::vector<std::uint32_t> offsets = {0, 2, 2, 3, 5, 5, 5, 5, 5, 6, 6, 8, 9};
  std::vector<std::uint32_t> columns = {1, 7, 3, 0, 23, 5, 2, 9, 4};
  std::vector<std::uint8_t> counts = {9, 1, 2, 3, 4, 1, 2, 5, 7};
  return TransferMatrix::from_csr(3, 4, 24, 3, std::move(offsets), columns, std::move(counts));
}

std::unique_ptr<CompressedTransfer> compress(const TransferMatrix& t,
                                             const std::map<std::string, std::string>& p = {}) {
  const CubemapLayout cubemap(2);
  const HemisphereGrid grid(2);
  return CompressorRegistry::instance()
      .create("uncompressed", p)
      ->compress({t, nullptr, cubemap, grid}, Progress::null());
}

TEST(Uncompressed, StorageIsTheCsrArraysByteForByte) {
  const TransferMatrix t = small_transfer();
  const auto ct = compress(t);
  const StorageReport r = ct->storage();
  ASSERT_EQ(r.components.size(), 4u);
  EXPECT_EQ(r.components[0].name, "row_offsets");
  EXPECT_EQ(r.components[0].bytes, (t.rows() + 1) * 4);
  EXPECT_EQ(r.components[1].name, "columns");
  EXPECT_EQ(r.components[1].bytes, t.nnz() * 2);
  EXPECT_NE(r.components[1].layout.find("u16"), std::string::npos);
  EXPECT_EQ(r.components[2].name, "counts");
  EXPECT_EQ(r.components[2].bytes, t.nnz());
  EXPECT_EQ(r.total_bytes(), t.memory_bytes() + 4);
  EXPECT_EQ(ct->flops_per_relight(), 2.0 * 9);
  EXPECT_EQ(ct->declared_error_bound(), 0.0);
  EXPECT_EQ(ct->output_basis(), RadianceBasis::kPixel);
}

TEST(Uncompressed, LightIsThePixelLightVectorAndRelightIsTheExactProduct) {
  const TransferMatrix t = small_transfer();
  const auto ct = compress(t);
  Cubemap light(2);
  for (std::size_t k = 0; k < light.radiance.size(); ++k)
    light.radiance[k] = Rgb(1.0f + k, 0.5f * k, 3.0f);
  const LightCoeffs coeffs = ct->project_light(light);
  EXPECT_EQ(coeffs.basis, "pixel");
  const auto expected = light.light_vector();
  ASSERT_EQ(coeffs.values.size(), expected.size());
  EXPECT_EQ(std::memcmp(coeffs.values.data(), expected.data(), expected.size() * sizeof(Rgb)), 0);

  LocalRadiance out;
  ct->relight(coeffs, out);
  const LocalRadiance exact = relight_exact(t, expected);
  EXPECT_EQ(out.dim, 4);
  EXPECT_EQ(out.vertices, 3u);
  ASSERT_EQ(out.values.size(), exact.values.size());
  EXPECT_EQ(std::memcmp(out.values.data(), exact.values.data(), out.values.size() * sizeof(Rgb)),
            0);
  // Row 0: count 9 (= 1.0) at column 1 and count 1 (= 1/9) at column 7.
  EXPECT_NEAR(out.values[0].z, expected[1].z + expected[7].z / 9.0, 1e-6);

  EXPECT_THROW(ct->project_light(Cubemap(4)), ParameterError);
  EXPECT_THROW(ct->relight(LightCoeffs{"sh5", expected}, out), ParameterError);
  EXPECT_THROW(ct->relight(LightCoeffs{"pixel", std::vector<Rgb>(23)}, out), ParameterError);
}

TEST(Uncompressed, LanesMustBeAPowerOfTwo) {
  const auto& registry = CompressorRegistry::instance();
  EXPECT_EQ(options_from(registry.device_options("uncompressed", {{"opencl_lanes", "16"}})).lanes,
            16);
  try {
    options_from(registry.device_options("uncompressed", {{"opencl_lanes", "12"}}));
    FAIL() << "accepted 12 lanes";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("power of two"), std::string::npos) << e.what();
  }
  EXPECT_THROW(registry.device_options("uncompressed", {{"opencl_kernel", "columns"}}),
               ParameterError);
}

TEST(Uncompressed, AutoPicksRowsOnCpusAndLanesOnGpus) {
  DeviceInfo cpu, gpu;
  cpu.is_cpu = true;
  gpu.is_gpu = true;
  EXPECT_EQ(resolve_variant(KernelVariant::kAuto, cpu), KernelVariant::kRows);
  EXPECT_EQ(resolve_variant(KernelVariant::kAuto, gpu), KernelVariant::kLanes);
  EXPECT_EQ(resolve_variant(KernelVariant::kLanes, cpu), KernelVariant::kLanes);
  EXPECT_EQ(resolve_variant(KernelVariant::kRows, gpu), KernelVariant::kRows);
  const auto& registry = CompressorRegistry::instance();
  for (auto v : {KernelVariant::kAuto, KernelVariant::kRows, KernelVariant::kLanes})
    EXPECT_EQ(options_from(registry.device_options("uncompressed",
                                                   {{"opencl_kernel", std::string(to_string(v))}}))
                  .kernel,
              v);
}

// Kernel variants are device options: not compression parameters, not saved, validated on
// upload (range by the spec, the power of two by options_from).
TEST(Uncompressed, KernelVariantsAreDeviceOptionsNotParameters) {
  EXPECT_THROW(compress(small_transfer(), {{"opencl_kernel", "lanes"}}), ParameterError);
  const auto& registry = CompressorRegistry::instance();
  const Options o = options_from(
      registry.device_options("uncompressed", {{"opencl_kernel", "lanes"}, {"opencl_lanes", "4"}}));
  EXPECT_EQ(o.kernel, KernelVariant::kLanes);
  EXPECT_EQ(o.lanes, 4);
  EXPECT_EQ(options_from(registry.device_options("uncompressed", {})).kernel, KernelVariant::kAuto);
  EXPECT_THROW(registry.device_options("uncompressed", {{"opencl_lanes", "64"}}), ParameterError);
  EXPECT_THROW(options_from(registry.device_options("uncompressed", {{"opencl_lanes", "3"}})),
               ParameterError);
  EXPECT_THROW(registry.device_options("uncompressed", {{"seed", "1"}}), ParameterError)
      << "the shared compression parameters are not device options";

  const fs::path file =
      fs::temp_directory_path() / ("prtlab_uncompressed_" + std::to_string(::getpid()) + ".prt");
  save_compressed(*compress(small_transfer()), file);
  const std::string bytes = [&] {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  const auto loaded = load_compressed(file);
  fs::remove(file);
  EXPECT_EQ(bytes.find("opencl"), std::string::npos) << "device options leaked into the file";
  const auto* u = dynamic_cast<const UncompressedTransfer*>(loaded.get());
  ASSERT_NE(u, nullptr);
  EXPECT_EQ(u->matrix(), small_transfer());
}

// A well-formed archive whose CSR arrays break T's invariants: load names the file.
TEST(Uncompressed, InconsistentFilesAreInputErrors) {
  const fs::path file = fs::temp_directory_path() /
                        ("prtlab_uncompressed_bad_" + std::to_string(::getpid()) + ".prt");
  auto write = [&](std::vector<std::uint8_t> counts, int version) {
    ArchiveWriter w("compressed-transfer", 1);
    w.add_meta("backend", "uncompressed");
    w.add_meta("flops_per_relight", 2.0);
    w.add_meta("storage_bytes", 1);
    w.add_meta("uncompressed_version", version);
    w.add_meta("vertices", 1);
    w.add_meta("local_count", 1);
    w.add_meta("pixel_count", 24);
    w.add_meta("supersampling", 2);
    w.add_section("row_offsets", std::vector<std::uint32_t>{0, 1});
    w.add_section("columns", std::vector<std::uint16_t>{3});
    w.add_section("counts", std::move(counts));
    w.write(file);
  };
  write({4}, kStateVersion);
  EXPECT_NO_THROW(load_compressed(file));
  write({5}, kStateVersion);  // count 5 > s^2 = 4
  try {
    load_compressed(file);
    ADD_FAILURE() << "loaded a count above s^2";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), file);
    EXPECT_NE(std::string(e.what()).find("count"), std::string::npos) << e.what();
  }
  write({4}, kStateVersion + 1);
  EXPECT_THROW(load_compressed(file), InputError);
  fs::remove(file);
}

}  // namespace
}  // namespace prt::uncompressed
