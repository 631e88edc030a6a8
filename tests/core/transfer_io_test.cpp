#include "prtlab/transfer/transfer_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "prtlab/base/error.h"
#include "prtlab/transfer/random_transfer.h"
#include "prtlab/transfer/scene_transfer.h"
#include "support/temp_dir.h"

namespace prt {
namespace {
namespace fs = std::filesystem;

class TransferFiles : public ::testing::Test {
 protected:
  prt::testing::TempDir tmp_{"transfer_io"};
  fs::path dir_ = tmp_.path();
};

TransferResult sample_result(bool with_sh) {
  TransferResult r;
  r.transfer = random_transfer(7, RandomTransferSpec{12, 4, 8, 2, 0.4, {3}});
  if (with_sh) {
    ShTransfer sh(3, r.transfer.vertex_count());
    auto data = sh.mutable_data();
    for (std::size_t i = 0; i < data.size(); ++i) data[i] = 0.001 * static_cast<double>(i) - 0.5;
    r.sh = std::move(sh);
  }
  r.stats.rays_traced = 12345;
  r.stats.seconds_total = 1.5;
  return r;
}

TEST_F(TransferFiles, SaveLoadIsBitExact) {
  for (bool with_sh : {false, true}) {
    const TransferResult r = sample_result(with_sh);
    const fs::path file = dir_ / "t.prt";
    save_transfer(r).write(file);
    const TransferResult back = load_transfer(ArchiveReader::open(file));
    EXPECT_TRUE(back.transfer == r.transfer);
    ASSERT_EQ(back.sh.has_value(), with_sh);
    if (with_sh) {
      EXPECT_TRUE(*back.sh == *r.sh);
    }
    EXPECT_EQ(back.stats.rays_traced, 12345u);
    EXPECT_EQ(back.stats.seconds_total, 1.5);
  }
}

TEST_F(TransferFiles, WideColumnsRoundTrip) {
  // N = 6 * 128^2 = 98,304 > 65,536: columns are stored as u32.
  TransferResult r;
  r.transfer = random_transfer(3, RandomTransferSpec{2, 2, 128, 2, 0.01, {}});
  ASSERT_FALSE(r.transfer.narrow_columns());
  const fs::path file = dir_ / "wide.prt";
  save_transfer(r).write(file);
  EXPECT_TRUE(load_transfer(ArchiveReader::open(file)).transfer == r.transfer);
}

TEST_F(TransferFiles, FlippedByteIsReportedWithTheFileName) {
  const fs::path file = dir_ / "t.prt";
  save_transfer(sample_result(true)).write(file);
  const auto size = fs::file_size(file);
  for (std::uintmax_t pos : {std::uintmax_t{40}, size / 2, size - 40}) {
    const fs::path bad = dir_ / "bad.prt";
    fs::copy_file(file, bad, fs::copy_options::overwrite_existing);
    {
      std::fstream f(bad, std::ios::in | std::ios::out | std::ios::binary);
      f.seekg(static_cast<std::streamoff>(pos));
      char c = 0;
      f.read(&c, 1);
      c = static_cast<char>(c ^ 0x10);
      f.seekp(static_cast<std::streamoff>(pos));
      f.write(&c, 1);
    }
    try {
      load_transfer(ArchiveReader::open(bad));
      FAIL() << "a flipped byte at " << pos << " was not detected";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("bad.prt"), std::string::npos) << e.what();
    }
  }
}

TEST_F(TransferFiles, InconsistentArraysAreAnInputError) {
  // A well-formed archive whose CSR breaks an invariant (a count above s^2) is refused by name.
  const TransferResult r = sample_result(false);
  ArchiveWriter w(std::string(kTransferArchiveKind), kTransferArchiveVersion);
  w.add_meta("vertices", r.transfer.vertex_count());
  w.add_meta("local_count", r.transfer.local_count());
  w.add_meta("pixel_count", r.transfer.cols());
  w.add_meta("supersampling", r.transfer.supersampling());
  w.add_meta("sh_order", 0);
  w.add_section("row_offsets", r.transfer.row_offsets());
  w.add_section("columns", r.transfer.columns16());
  std::vector<std::uint8_t> counts(r.transfer.counts().begin(), r.transfer.counts().end());
  ASSERT_FALSE(counts.empty());
  counts[0] = 9;  // s = 2 allows 1..4
  w.add_section("counts", std::move(counts));
  const fs::path file = dir_ / "inconsistent.prt";
  w.write(file);
  try {
    load_transfer(ArchiveReader::open(file));
    FAIL() << "accepted a count above s^2";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("inconsistent.prt"), std::string::npos) << e.what();
  }
}

TEST_F(TransferFiles, SecondPrecomputeIsACacheHitWithTheSameMatrix) {
  const fs::path scene = fs::path(PRTLAB_SOURCE_DIR) / "scenes" / "tiny-sphere-plane.toml";
  StageCache cache(dir_ / "cache");
  PrecomputeOptions opt;
  opt.show_progress = false;
  const SceneDesc desc = parse_scene(scene);
  const SceneTransfer first = precompute_scene_transfer(desc, opt, cache);
  const SceneTransfer second = precompute_scene_transfer(desc, opt, cache);
  EXPECT_FALSE(first.cache_hit);
  EXPECT_TRUE(second.cache_hit);
  EXPECT_TRUE(first.result.transfer == second.result.transfer);
  EXPECT_EQ(first.key, second.key);
  EXPECT_GT(first.result.transfer.nnz(), 0u);
  // Asking for the SH transfer is a different stage result (a different key).
  opt.sh_order = 2;
  const SceneTransfer with_sh = precompute_scene_transfer(desc, opt, cache);
  EXPECT_FALSE(with_sh.cache_hit);
  EXPECT_NE(with_sh.key, first.key);
  ASSERT_TRUE(with_sh.result.sh.has_value());
  EXPECT_TRUE(with_sh.result.transfer == first.result.transfer);
}

// Camera presets do not change T: editing only [[view]] tables keeps the cache key, while any
// edit that changes the transfer (here the cubemap resolution) changes it.
TEST_F(TransferFiles, ViewOnlyEditKeepsTheSceneInputHash) {
  const fs::path src = fs::path(PRTLAB_SOURCE_DIR) / "scenes" / "tiny-sphere-plane.toml";
  std::ifstream in(src);
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  const auto write = [&](const std::string& name, const std::string& body) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << body;
    return parse_scene(p);
  };
  const Hash128 base = scene_input_hash(write("a.toml", text));
  const Hash128 more_views = scene_input_hash(
      write("b.toml", text + "\n[[view]]\nname = \"side\"\nfrom = [1.0, 0.2, 0.0]\n"));
  EXPECT_EQ(base, more_views);
  std::string finer = text;
  const auto at = finer.find("cubemap_resolution = 8");
  ASSERT_NE(at, std::string::npos);
  finer.replace(at, 22, "cubemap_resolution = 6");
  EXPECT_NE(base, scene_input_hash(write("c.toml", finer)));
}

}  // namespace
}  // namespace prt
