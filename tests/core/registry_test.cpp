// The compressor and material registries: the built-in backends are all present (a backend
// dropped by the linker or by a broken glob fails here), lookups of unknown names list the
// registered ones, duplicates and incomplete entries are refused, plugins that are missing or are
// not prtlab plugins give clear errors, and compressed transfers round-trip through save_compressed
// / load_compressed with the backend named in the file.
#include <dlfcn.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "prtlab/base/error.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/storage/archive.h"
#include "prtlab/transfer/transfer_matrix.h"
#include "support/temp_dir.h"

namespace prt {
namespace {
namespace fs = std::filesystem;

// Every backend folder, built-in (compressors/<name>/) and test-only (tests/backends/<name>/,
// linked into the tests): each registers the backend its folder is named after, a transfer
// compressor or a material (two registries, one set of folder names). A backend
// whose registrar is lost (linker, glob, a renamed folder) fails here instead of silently
// disappearing from every table, and nobody keeps a list of names by hand.
std::vector<std::string> backend_folders() {
  std::vector<std::string> names;
  for (const char* root : {"compressors", "tests/backends"}) {
    const fs::path dir = fs::path(PRTLAB_SOURCE_DIR) / root;
    if (!fs::exists(dir)) continue;
    for (const auto& entry : fs::directory_iterator(dir))
      if (entry.is_directory()) names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}
const std::vector<std::string> kBuiltinBackends = backend_folders();

// The folders that are transfer compressors: all but the registered materials.
std::vector<std::string> transfer_folders() {
  std::vector<std::string> out;
  for (const auto& n : kBuiltinBackends)
    if (!MaterialRegistry::instance().contains(n)) out.push_back(n);
  return out;
}

using ScratchDir = testing::TempDir;

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no exception)";
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

CompressorEntry dummy_entry(std::string name) {
  CompressorEntry e;
  e.name = std::move(name);
  e.description = "test entry";
  e.create = [](const ParamSet&) -> std::unique_ptr<Compressor> { return nullptr; };
  e.load = [](const ArchiveReader&) -> std::unique_ptr<CompressedTransfer> { return nullptr; };
  return e;
}

// 2 vertices, M = 4, N = 24 (R = 2), s = 2: a few entries with distinct counts.
TransferMatrix small_transfer() {
  std::vector<std::uint32_t> offsets = {0, 2, 2, 3, 3, 5, 6, 6, 7};
  std::vector<std::uint32_t> columns = {1, 7, 3, 0, 23, 5, 7};
  std::vector<std::uint8_t> counts = {4, 1, 2, 3, 4, 1, 2};
  return TransferMatrix::from_csr(2, 4, 24, 2, std::move(offsets), columns, std::move(counts));
}

TEST(Registry, HoldsEveryBuiltinBackendComplete) {
  const auto& registry = CompressorRegistry::instance();
  const auto names = registry.names();
  const auto material_names = MaterialRegistry::instance().names();
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
  EXPECT_EQ(std::adjacent_find(names.begin(), names.end()), names.end());
  ASSERT_GE(kBuiltinBackends.size(), 3u) << "no backend folders found under " PRTLAB_SOURCE_DIR;
  // The folders are exactly the transfer names and the material names, and no name is both.
  std::vector<std::string> all = names;
  all.insert(all.end(), material_names.begin(), material_names.end());
  std::sort(all.begin(), all.end());
  EXPECT_EQ(std::adjacent_find(all.begin(), all.end()), all.end())
      << "a name is registered both as a transfer compressor and as a material";
  EXPECT_EQ(all, kBuiltinBackends) << "registered backends differ from the backend folders";
  EXPECT_EQ(names, transfer_folders());
  for (const auto& name : transfer_folders()) {
    ASSERT_TRUE(registry.contains(name)) << "built-in backend '" << name << "' is not registered";
    const auto& e = registry.get(name);
    EXPECT_EQ(e.name, name);
    EXPECT_EQ(e.origin, "built-in");
    EXPECT_FALSE(e.description.empty());
    EXPECT_TRUE(e.create && e.load);
  }
  EXPECT_TRUE(registry.get("uncompressed").lossless);
  for (const auto& name : material_names) {
    const auto& e = MaterialRegistry::instance().get(name);
    EXPECT_EQ(e.name, name);
    EXPECT_EQ(e.origin, "built-in");
    EXPECT_FALSE(e.description.empty());
    EXPECT_TRUE(e.create && e.load);
  }
  ASSERT_TRUE(MaterialRegistry::instance().contains("full"));
  EXPECT_TRUE(MaterialRegistry::instance().get("full").lossless);
}

MaterialEntry dummy_material(std::string name) {
  MaterialEntry e;
  e.name = std::move(name);
  e.description = "test entry";
  e.create = [](const ParamSet&) -> std::unique_ptr<MaterialCompressor> { return nullptr; };
  e.load = [](const ArchiveReader&) -> std::unique_ptr<CompressedMaterial> { return nullptr; };
  return e;
}

TEST(MaterialRegistry, RefusesDuplicatesIncompleteEntriesAndUnknownNames) {
  MaterialRegistry local;
  local.add(dummy_material("alpha"));
  const std::string dup = message_of([&] { local.add(dummy_material("alpha")); });
  EXPECT_TRUE(contains(dup, "alpha") && contains(dup, "twice")) << dup;
  EXPECT_THROW(local.add(dummy_material("")), Error);
  MaterialEntry no_load = dummy_material("beta");
  no_load.load = nullptr;
  EXPECT_THROW(local.add(no_load), Error);
  MaterialEntry clash = dummy_material("gamma");
  clash.params = {{"k", ParamType::kInt, "1", 1.0, 8.0, {}, "levels"}};
  clash.device_params = clash.params;
  EXPECT_THROW(local.add(clash), Error);
  EXPECT_EQ(local.names(), std::vector<std::string>{"alpha"});

  const auto& global = MaterialRegistry::instance();
  const std::string msg = message_of([&] { global.create("no-such-material", {}); });
  EXPECT_TRUE(contains(msg, "no-such-material") && contains(msg, "full")) << msg;
  EXPECT_THROW(global.create("full", {{"no_such_key", "1"}}), ParameterError);
  EXPECT_NE(global.create("full", {{"seed", "3"}}), nullptr);
}

TEST(Registry, UnknownBackendListsTheRegisteredOnes) {
  const auto& registry = CompressorRegistry::instance();
  EXPECT_FALSE(registry.contains("no-such-backend"));
  EXPECT_THROW(registry.get("no-such-backend"), ParameterError);
  const std::string msg = message_of([&] { registry.create("no-such-backend", {}); });
  EXPECT_TRUE(contains(msg, "no-such-backend")) << msg;
  for (const auto& name : transfer_folders()) EXPECT_TRUE(contains(msg, name)) << msg;
}

TEST(Registry, RefusesDuplicatesAndIncompleteEntries) {
  CompressorRegistry local;
  local.add(dummy_entry("alpha"));
  EXPECT_TRUE(local.contains("alpha"));
  const std::string dup = message_of([&] { local.add(dummy_entry("alpha")); });
  EXPECT_TRUE(contains(dup, "alpha") && contains(dup, "twice")) << dup;
  EXPECT_EQ(local.names(), std::vector<std::string>{"alpha"});

  EXPECT_THROW(local.add(dummy_entry("")), Error);
  CompressorEntry no_load = dummy_entry("beta");
  no_load.load = nullptr;
  EXPECT_THROW(local.add(no_load), Error);
  CompressorEntry no_create = dummy_entry("gamma");
  no_create.create = nullptr;
  EXPECT_THROW(local.add(no_create), Error);
  // A backend whose own parameter defaults are invalid fails at registration, not at first use.
  CompressorEntry bad_default = dummy_entry("delta");
  bad_default.params = {{"k", ParamType::kInt, "0", 1.0, 8.0, {}, "must be 1..8"}};
  EXPECT_THROW(local.add(bad_default), Error);
  EXPECT_EQ(local.names(), std::vector<std::string>{"alpha"});
  // A light option (run-time, never compressed) may not reuse a parameter's, a device option's
  // or a shared parameter's key: a point's parameters hold them side by side.
  const ParamSpec n{"n", ParamType::kInt, "1", 1.0, 8.0, {}, "a count"};
  for (const auto& [where, clash] : std::vector<std::pair<std::string, CompressorEntry>>{
           {"a parameter", dummy_entry("epsilon")},
           {"a device option", dummy_entry("zeta")},
           {"a shared parameter", dummy_entry("eta")}}) {
    CompressorEntry e = clash;
    e.light_params = {n};
    if (where == "a parameter") e.params.push_back(n);
    if (where == "a device option") e.device_params = {n};
    if (where == "a shared parameter") e.light_params[0].key = "seed";
    const std::string msg = message_of([&] { local.add(e); });
    EXPECT_TRUE(contains(msg, where) && contains(msg, "a light option")) << msg;
  }
  CompressorEntry light = dummy_entry("theta");
  light.light_params = {n};
  local.add(light);
  EXPECT_EQ(local.light_options("theta", {{"n", "3"}}).get_int("n"), 3);
  EXPECT_THROW(local.light_options("theta", {{"n", "9"}}), ParameterError);
  EXPECT_THROW(local.light_options("alpha", {{"n", "3"}}), ParameterError);
  EXPECT_EQ(local.names(), (std::vector<std::string>{"alpha", "theta"}));

  // The global registry refuses a second 'uncompressed' and keeps the first.
  auto& global = CompressorRegistry::instance();
  const auto before = global.names();
  EXPECT_THROW(global.add(dummy_entry("uncompressed")), Error);
  EXPECT_EQ(global.names(), before);
  EXPECT_EQ(global.get("uncompressed").origin, "built-in");
}

TEST(Registry, CreateValidatesParameters) {
  const auto& registry = CompressorRegistry::instance();
  EXPECT_NE(registry.create("uncompressed", {}), nullptr);
  EXPECT_NE(registry.create("uncompressed", {{"seed", "3"}}), nullptr);
  const std::string msg = message_of([&] { registry.create("uncompressed", {{"sede", "3"}}); });
  EXPECT_TRUE(contains(msg, "sede") && contains(msg, "seed")) << msg;
  EXPECT_THROW(registry.create("uncompressed", {{"seed", "-1"}}), ParameterError);
}

TEST(Plugins, MissingFileIsAClearError) {
  const fs::path missing = fs::temp_directory_path() / "prtlab_no_such_plugin.so";
  try {
    load_plugin(missing);
    FAIL() << "loaded a missing plugin";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), missing);
    EXPECT_TRUE(contains(e.what(), "not found")) << e.what();
  }
}

// The C library's math library is a shared object on every Linux machine; it has neither
// entry point.
fs::path libm_path() {
  Dl_info info{};
  if (::dladdr(reinterpret_cast<void*>(static_cast<double (*)(double)>(&::erfc)), &info) != 0 &&
      info.dli_fname && contains(info.dli_fname, "libm"))
    return info.dli_fname;
  for (const char* p :
       {"/lib/x86_64-linux-gnu/libm.so.6", "/usr/lib/x86_64-linux-gnu/libm.so.6",
        "/lib/aarch64-linux-gnu/libm.so.6", "/lib64/libm.so.6", "/usr/lib64/libm.so.6"})
    if (fs::exists(p)) return p;
  return {};
}

TEST(Plugins, SharedObjectWithoutEntryPointsIsRefused) {
  const fs::path libm = libm_path();
  if (libm.empty()) GTEST_SKIP() << "no libm.so.6 found on this machine";
  const auto before = CompressorRegistry::instance().names();
  try {
    load_plugin(libm);
    FAIL() << "accepted " << libm << " as a plugin";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "not a prtlab plugin")) << e.what();
    EXPECT_TRUE(contains(e.what(), "PRT_REGISTER_COMPRESSOR")) << e.what();
    EXPECT_TRUE(contains(e.what(), libm.string())) << e.what();
  }
  EXPECT_EQ(CompressorRegistry::instance().names(), before);
}

TEST(Plugins, FileThatIsNoLibraryIsRefused) {
  ScratchDir dir;
  const fs::path fake = dir.path() / "fake_plugin.so";
  std::ofstream(fake) << "not an ELF file\n";
  try {
    load_plugin(fake);
    FAIL() << "loaded a text file";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "cannot load plugin")) << e.what();
    EXPECT_EQ(e.file(), fake);
  }
}

TEST(CompressedFiles, SaveLoadRoundTripThroughTheRegistry) {
  ScratchDir dir;
  const TransferMatrix t = small_transfer();
  const CubemapLayout cubemap(2);
  const HemisphereGrid grid(2);
  const auto compressed = CompressorRegistry::instance()
                              .create("uncompressed", {})
                              ->compress({t, nullptr, cubemap, grid}, Progress::null());
  const fs::path file = dir.path() / "t.prt";
  save_compressed(*compressed, file);

  const ArchiveReader archive = ArchiveReader::open(file);
  EXPECT_EQ(archive.kind(), "compressed-transfer");
  EXPECT_EQ(archive.meta_value<std::string>("backend"), "uncompressed");
  EXPECT_EQ(archive.meta_value<double>("flops_per_relight"), 2.0 * t.nnz());
  EXPECT_EQ(archive.meta_value<std::uint64_t>("storage_bytes"),
            compressed->storage().total_bytes());

  const auto loaded = load_compressed(file);
  ASSERT_NE(loaded, nullptr);
  EXPECT_EQ(loaded->backend(), "uncompressed");
  EXPECT_EQ(loaded->storage().total_bytes(), compressed->storage().total_bytes());
  Cubemap light(2);
  for (std::size_t k = 0; k < light.radiance.size(); ++k)
    light.radiance[k] = Rgb(0.5f + static_cast<float>(k), 1.0f, 2.0f * static_cast<float>(k));
  LocalRadiance a, b;
  compressed->relight(compressed->project_light(light), a);
  loaded->relight(loaded->project_light(light), b);
  ASSERT_EQ(a.values.size(), t.rows());
  ASSERT_EQ(b.values.size(), t.rows());
  EXPECT_EQ(std::memcmp(a.values.data(), b.values.data(), a.values.size() * sizeof(Rgb)), 0);
  // Row 0 is counts 4 and 1 at columns 1 and 7 times 1/4: a hand-computed value, not only a
  // comparison of two relights.
  const auto l = light.light_vector();
  EXPECT_NEAR(a.values[0].x, l[1].x + 0.25 * l[7].x, 1e-6 * std::abs(l[1].x + 0.25 * l[7].x));
  EXPECT_EQ(a.values[1], Rgb(0.f));  // an empty row
}

TEST(CompressedFiles, UnregisteredBackendIsAClearError) {
  ScratchDir dir;
  const fs::path file = dir.path() / "foreign.prt";
  ArchiveWriter w("compressed-transfer", 1);
  w.add_meta("backend", "no-such-backend");
  w.add_meta("flops_per_relight", 1.0);
  w.add_meta("storage_bytes", 1);
  w.add_section("payload", std::vector<std::uint8_t>{1, 2, 3});
  w.write(file);
  try {
    load_compressed(file);
    FAIL() << "loaded a file of an unregistered backend";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(e.file(), file);
    EXPECT_TRUE(contains(msg, "no-such-backend")) << msg;
    EXPECT_TRUE(contains(msg, "not registered")) << msg;
    EXPECT_TRUE(contains(msg, "--plugin")) << msg;
    for (const auto& name : transfer_folders()) EXPECT_TRUE(contains(msg, name)) << msg;
  }
}

TEST(CompressedFiles, OtherArtifactKindsAndDamagedFilesAreRefused) {
  ScratchDir dir;
  const fs::path other = dir.path() / "other.prt";
  ArchiveWriter w("transfer-matrix", 1);
  w.add_meta("backend", "uncompressed");
  w.write(other);
  const std::string msg = message_of([&] { load_compressed(other); });
  EXPECT_TRUE(contains(msg, "transfer-matrix") && contains(msg, "compressed-transfer")) << msg;

  // A valid compressed file with one byte flipped: the checksum refuses it before any backend
  // code reads it.
  const TransferMatrix t = small_transfer();
  const CubemapLayout cubemap(2);
  const HemisphereGrid grid(2);
  const fs::path file = dir.path() / "t.prt";
  save_compressed(*CompressorRegistry::instance()
                       .create("uncompressed", {})
                       ->compress({t, nullptr, cubemap, grid}, Progress::null()),
                  file);
  {
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    const auto middle = static_cast<std::streamoff>(fs::file_size(file) / 2);
    f.seekg(middle);
    const char byte = static_cast<char>(f.get());
    f.seekp(middle);
    f.put(static_cast<char>(~byte));
  }
  EXPECT_THROW(load_compressed(file), InputError);
}

}  // namespace
}  // namespace prt
