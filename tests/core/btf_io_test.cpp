// BTF archives and the BTF stage: bit-exact round trips, corrupt or foreign files reported,
// cache hits identical to misses, keys that follow the parameters, and the CLI commands.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "prtlab/btf/btf.h"
#include "prtlab/btf/btf_generator.h"
#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "support/cli_runner.h"

namespace prt {
namespace {

namespace fs = std::filesystem;

class BtfIo : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / fmt::format("prtlab_btf_io_{}_{}", ::getpid(), info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  static BtfParams tiny() {
    BtfParams p;
    p.resolution = 8;
    p.view_side = 4;
    p.light_side = 4;
    return p;
  }
  fs::path dir_;
};

bool bitwise_equal(const Btf& a, const Btf& b) {
  return a.bytes() == b.bytes() && std::memcmp(a.data().data(), b.data().data(), a.bytes()) == 0;
}

TEST_F(BtfIo, SaveLoadIsBitExact) {
  const Btf b = generate_btf(make_btf_material("checker", 64), tiny());
  const fs::path file = dir_ / "checker.prt";
  write_btf(b, file);
  const Btf r = read_btf(file);
  EXPECT_TRUE(bitwise_equal(b, r));
  EXPECT_EQ(r.material(), "checker");
  EXPECT_EQ(r.resolution(), 8);
  EXPECT_EQ(r.view_side(), 4);
  EXPECT_EQ(r.light_side(), 4);
  EXPECT_EQ(r.parameters(), b.parameters());
  EXPECT_EQ(r.view_independent(), b.view_independent());
}

TEST_F(BtfIo, CorruptFileIsReported) {
  const fs::path file = dir_ / "b.prt";
  write_btf(generate_btf(make_btf_material("lambert"), tiny()), file);
  {
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(fs::file_size(file) / 2));
    f.put('\x5a');
  }
  try {
    read_btf(file);
    FAIL() << "a corrupt file was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("checksum mismatch"), std::string::npos) << e.what();
    EXPECT_EQ(e.file(), file);
  }
}

TEST_F(BtfIo, ForeignArchivesAreRefused) {
  const fs::path other = dir_ / "other.prt";
  ArchiveWriter w("transfer-matrix", 1);
  w.add_section("x", std::vector<float>{1.f});
  w.write(other);
  EXPECT_THROW(read_btf(other), InputError);

  // A BTF whose view directions are not the concentric grid's (another convention).
  ArchiveWriter bad = save_btf(generate_btf(make_btf_material("lambert"), tiny()));
  ArchiveWriter forged(kBtfArchiveKind, kBtfArchiveVersion);
  forged.meta() = bad.meta();
  const ArchiveReader good = ArchiveReader::from_bytes(bad.to_bytes(), "mem");
  forged.add_section("rgb", good.section<float>("rgb"));
  auto views = good.section<float>("view_directions");
  views[3] += 0.01f;  // view 1 moved by 0.01
  forged.add_section("view_directions", std::move(views));
  forged.add_section("light_directions", good.section<float>("light_directions"));
  const fs::path file = dir_ / "forged.prt";
  forged.write(file);
  try {
    read_btf(file);
    FAIL() << "a BTF with foreign view directions was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("view_directions"), std::string::npos) << e.what();
  }
}

TEST_F(BtfIo, StageCacheHitEqualsMissAndKeysFollowParameters) {
  StageCache cache(dir_ / "cache");
  const auto first = generate_btf_cached("bumps", tiny(), cache);
  EXPECT_FALSE(first.cache_hit);
  EXPECT_TRUE(fs::exists(first.cache_file));
  const auto second = generate_btf_cached("bumps", tiny(), cache);
  EXPECT_TRUE(second.cache_hit);
  EXPECT_EQ(first.key, second.key);
  EXPECT_TRUE(bitwise_equal(first.btf, second.btf));
  // The cached BTF equals a direct generation.
  BtfParams p = tiny();
  EXPECT_TRUE(bitwise_equal(
      first.btf, generate_btf(make_btf_material("bumps", p.effective_geometry_grid()), p)));

  p.light_side = 3;
  const auto other = generate_btf_cached("bumps", p, cache);
  EXPECT_FALSE(other.cache_hit);
  EXPECT_NE(other.key, first.key);
  const auto mat = generate_btf_cached("stucco", tiny(), cache);
  EXPECT_NE(mat.key, first.key);
  // --force regenerates.
  const auto forced = generate_btf_cached("bumps", tiny(), cache, CacheMode::kRefresh);
  EXPECT_FALSE(forced.cache_hit);
  EXPECT_TRUE(bitwise_equal(forced.btf, first.btf));
}

TEST_F(BtfIo, CliGenerateInfoPreview) {
  const std::string env = "PRTLAB_CACHE=\"" + (dir_ / "cache").string() + "\" ";
  const std::string size = " --res 4 --views 2 --lights 2";
  const fs::path out = dir_ / "l.prt", png = dir_ / "p.png";
  auto r = prt::testing::run_cli(
      "btf generate lambert" + size + " --json --out \"" + out.string() + "\"", dir_, env);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["material"], "lambert");
  EXPECT_EQ(j["lights"], 4);
  EXPECT_EQ(j["cache_hit"], false);
  EXPECT_TRUE(j["view_independent"].get<bool>());
  EXPECT_NEAR(j["albedo_mean"][0].get<double>(), 0.8, 0.05);
  EXPECT_TRUE(j.contains("prtlab"));
  EXPECT_TRUE(fs::exists(out));

  r = prt::testing::run_cli("btf info \"" + out.string() + "\" --json", dir_, env);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["source"], "file");
  EXPECT_EQ(j["albedo_per_light"].size(), 4u);

  r = prt::testing::run_cli("btf preview lambert" + size + " --out \"" + png.string() + "\"", dir_,
                            env);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(png));

  r = prt::testing::run_cli("btf info velvet", dir_, env);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("velvet"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("checker"), std::string::npos) << r.err;  // lists the valid names
}

}  // namespace
}  // namespace prt
