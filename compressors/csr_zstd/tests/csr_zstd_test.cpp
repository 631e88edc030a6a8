// Backend `csr_zstd`, beyond the conformance suite: the frames decompress to T's arrays bit for
// bit (every frame size, narrow and wide columns, empty rows and vertices), the relight is the
// exact product within a derived float-rounding bound, the byte accounting, save/load, OpenCL
// against C++, and refusal of corrupt, truncated or inconsistent files.
#include "csr_zstd/csr_zstd.h"

#include <gtest/gtest.h>
#include <zstd.h>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "prtlab/base/error.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/opencl/cl_buffer.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/storage/archive.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/transfer/random_transfer.h"
#include "support/temp_dir.h"
#include "support/test_light.h"

namespace prt::csr_zstd {
namespace {
namespace fs = std::filesystem;

const fs::path g_cache_root = prt::testing::use_private_cache("csr_zstd");

// 11 vertices, M = 16, N = 96 (R = 4), s = 3, two empty vertices: 176 rows.
TransferMatrix test_transfer() {
  return random_transfer(3, RandomTransferSpec{11, 4, 4, 3, 0.6, {2, 7}});
}
// N = 98,304 > 65,536: u32 columns.
TransferMatrix wide_transfer() {
  return random_transfer(17, RandomTransferSpec{4, 2, 128, 2, 0.003, {}});
}

std::unique_ptr<CompressedTransfer> compress(const TransferMatrix& t, int level, int block_rows) {
  const CubemapLayout cubemap(static_cast<int>(std::lround(std::sqrt(t.cols() / 6.0))));
  const HemisphereGrid grid(static_cast<int>(std::lround(std::sqrt(t.local_count()))));
  return CompressorRegistry::instance()
      .create(std::string(kName),
              {{"level", std::to_string(level)}, {"block_rows", std::to_string(block_rows)}})
      ->compress({t, nullptr, cubemap, grid}, Progress::null());
}

const FramedCsr& frames(const CompressedTransfer& ct) {
  return dynamic_cast<const CsrZstdTransfer&>(ct).frames();
}

std::vector<Rgb> test_light(std::size_t n, std::uint64_t seed) {
  return prt::testing::pseudo_random_light(n, seed, 4.0f);
}

TEST(CsrZstd, FramesDecompressToTsArraysBitForBit) {
  for (const TransferMatrix& t : {test_transfer(), wide_transfer()}) {
    ASSERT_GT(t.nnz(), 0u);
    for (int block_rows : {1, 7, 16, 1000}) {
      for (int level : {1, 19}) {
        SCOPED_TRACE(
            fmt::format("N = {}, block_rows = {}, level = {}", t.cols(), block_rows, level));
        const auto ct = compress(t, level, block_rows);
        const FramedCsr& csr = frames(*ct);
        EXPECT_EQ(csr.frame_count(), (t.rows() + block_rows - 1) / block_rows);
        EXPECT_TRUE(decompress_all(csr) == t);
        // Each frame is a zstd frame of its own that says its size (what lets frames decompress
        // independently).
        for (std::size_t f = 0; f < csr.frame_count(); ++f) {
          const std::uint8_t* frame = csr.frames.data() + csr.frame_offsets[f];
          const std::size_t bytes = csr.frame_offsets[f + 1] - csr.frame_offsets[f];
          ASSERT_EQ(ZSTD_findFrameCompressedSize(frame, bytes), bytes) << "frame " << f;
          ASSERT_EQ(ZSTD_getFrameContentSize(frame, bytes), csr.frame_raw_bytes(f));
        }
      }
    }
  }
}

// Every row within (n + 2) 2^-24 of the double product, relative to that row: the standard
// bound for a float sum of n non-negative terms, the scale multiply and the count conversion.
TEST(CsrZstd, RelightIsTheExactProductWithinFloatRounding) {
  for (const TransferMatrix& t : {test_transfer(), wide_transfer()}) {
    const auto ct = compress(t, 3, 16);
    for (std::uint64_t seed : {1u, 2u}) {
      const std::vector<Rgb> light = test_light(t.cols(), seed);
      LocalRadiance out;
      ct->relight({"pixel", light}, out);
      const std::vector<Vec3d> exact = relight_exact_double(t, light);
      ASSERT_EQ(out.values.size(), exact.size());
      for (std::size_t row = 0; row < t.rows(); ++row) {
        const double n = t.row_offsets()[row + 1] - t.row_offsets()[row];
        for (int c = 0; c < 3; ++c)
          ASSERT_LE(std::abs(out.values[row][c] - exact[row][c]), (n + 2) * 0x1p-24 * exact[row][c])
              << "row " << row << " channel " << c;
      }
    }
  }
}

TEST(CsrZstd, StorageIsTheFramesAndTheirOffsets) {
  const TransferMatrix t = test_transfer();
  const auto ct = compress(t, 3, 16);
  const FramedCsr& csr = frames(*ct);
  const std::uint64_t n = csr.frame_count();
  ASSERT_EQ(n, 11u);  // 176 rows / 16
  const StorageReport r = ct->storage();
  ASSERT_EQ(r.components.size(), 4u);
  EXPECT_EQ(r.components[0].name, "frames");
  EXPECT_EQ(r.components[0].bytes, csr.frames.size());
  EXPECT_EQ(r.components[1].bytes, 8 * (n + 1));
  EXPECT_EQ(r.components[2].bytes, 4 * (n + 1));
  EXPECT_EQ(r.total_bytes(), csr.frames.size() + 12 * (n + 1) + 4);
  EXPECT_EQ(ct->flops_per_relight(), 2.0 * static_cast<double>(t.nnz()));
  EXPECT_EQ(ct->declared_error_bound(), 0.0);
  // A frame per row holds the same data with 176 frame headers: more bytes.
  EXPECT_GT(compress(t, 3, 1)->storage().total_bytes(), r.total_bytes());
}

TEST(CsrZstd, EmptyTransferHasNoEntriesAndRelightsToZero) {
  const TransferMatrix t = random_transfer(5, RandomTransferSpec{3, 2, 2, 2, 0.0, {}});
  ASSERT_EQ(t.nnz(), 0u);
  const auto ct = compress(t, 3, 5);
  EXPECT_TRUE(decompress_all(frames(*ct)) == t);
  LocalRadiance out;
  ct->relight({"pixel", test_light(t.cols(), 1)}, out);
  for (const Rgb& v : out.values) EXPECT_EQ(v, Rgb(0.f));
}

TEST(CsrZstd, SaveLoadRoundTripIsExact) {
  const TransferMatrix t = test_transfer();
  prt::testing::TempDir dir("csr_zstd");
  const auto ct = compress(t, 5, 32);
  const fs::path file = dir / "t.prt";
  save_compressed(*ct, file);
  const auto loaded = load_compressed(file);
  ASSERT_EQ(loaded->backend(), "csr_zstd");
  const FramedCsr &a = frames(*ct), &b = frames(*loaded);
  EXPECT_EQ(a.frames, b.frames);
  EXPECT_EQ(a.frame_offsets, b.frame_offsets);
  EXPECT_EQ(a.frame_entries, b.frame_entries);
  EXPECT_EQ(b.level, 5);
  EXPECT_EQ(b.block_rows, 32);
  const std::vector<Rgb> light = test_light(t.cols(), 7);
  LocalRadiance x, y;
  ct->relight({"pixel", light}, x);
  loaded->relight({"pixel", light}, y);
  ASSERT_EQ(x.values.size(), y.values.size());
  EXPECT_EQ(std::memcmp(x.values.data(), y.values.data(), x.values.size() * sizeof(Rgb)), 0);
}

TEST(CsrZstd, OpenClMatchesTheCppRelight) {
  ClContext* ctx = default_context();
  if (ctx == nullptr) GTEST_SKIP() << "no OpenCL device";
  for (const TransferMatrix& t : {test_transfer(), wide_transfer()}) {
    SCOPED_TRACE(fmt::format("N = {}", t.cols()));
    const auto ct = compress(t, 3, 16);
    auto device = upload_compressed(*ct, *ctx);
    ASSERT_NE(device, nullptr);
    // Two lights on one upload: every relight decompresses and uploads again.
    for (std::uint64_t seed : {1u, 2u}) {
      const std::vector<Rgb> light = test_light(t.cols(), seed);
      LocalRadiance cpp, gpu;
      ct->relight({"pixel", light}, cpp);
      const double ms = device->relight({"pixel", light}, gpu);
      EXPECT_GT(ms, 0.0) << "decompression + upload + kernel take time";
      EXPECT_LE(max_relative_error(gpu, cpp), 1e-5);
    }
  }
}

// M = 16 and 24-row frames: vertices straddle frame boundaries.
TEST(CsrZstd, FrameTasksAreTheFramesHoldingTheSubsetsRows) {
  const auto ct = compress(test_transfer(), 3, 24);
  const std::vector<std::uint32_t> subset{0, 2, 3, 10};
  const std::vector<FrameTask> tasks = frame_tasks(frames(*ct), subset);
  // Rows 0..15 (frame 0), 32..47 (frame 1), 48..63 (frame 2), 160..175 (frames 6 and 7).
  const std::vector<std::array<std::size_t, 3>> want{
      {0, 0, 1}, {1, 1, 2}, {2, 2, 3}, {6, 3, 4}, {7, 3, 4}};
  ASSERT_EQ(tasks.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) {
    EXPECT_EQ(tasks[i].frame, want[i][0]) << i;
    EXPECT_EQ(tasks[i].vertex_begin, want[i][1]) << i;
    EXPECT_EQ(tasks[i].vertex_end, want[i][2]) << i;
  }
  EXPECT_TRUE(frame_tasks(frames(*ct), {}).empty());
}

// The subset relight writes the full relight's bits on the subset's rows and nothing elsewhere,
// and decompresses only the frames holding them: with frame 4 (rows 96..119, vertices 6 and 7)
// destroyed, a subset avoiding it still relights, one touching it fails. Bad subsets are refused.
TEST(CsrZstd, VertexSubsetDecompressesOnlyItsFramesAndHasTheFullBits) {
  const TransferMatrix t = test_transfer();
  const auto ct = compress(t, 3, 24);
  const std::vector<Rgb> light = test_light(t.cols(), 5);
  LocalRadiance full;
  ct->relight({"pixel", light}, full);
  FramedCsr broken = frames(*ct);
  std::fill(broken.frames.begin() + static_cast<std::ptrdiff_t>(broken.frame_offsets[4]),
            broken.frames.begin() + static_cast<std::ptrdiff_t>(broken.frame_offsets[5]),
            std::uint8_t{0});
  const CsrZstdTransfer partial(std::move(broken));
  const std::vector<std::uint32_t> subset{0, 2, 3, 5, 10};
  std::vector<bool> in(t.vertex_count(), false);
  for (const std::uint32_t v : subset) in[v] = true;
  LocalRadiance out = full;
  std::fill(out.values.begin(), out.values.end(), Rgb(-7.f));
  partial.relight_vertices({"pixel", light}, subset, out);
  for (std::size_t r = 0; r < out.values.size(); ++r) {
    const Rgb want = in[r / 16] ? full.values[r] : Rgb(-7.f);
    EXPECT_EQ(std::memcmp(&out.values[r], &want, sizeof(Rgb)), 0) << "row " << r;
  }
  EXPECT_THROW(partial.relight_vertices({"pixel", light}, std::vector<std::uint32_t>{6}, out),
               ParameterError);
  for (const std::vector<std::uint32_t>& bad :
       {std::vector<std::uint32_t>{3, 1}, std::vector<std::uint32_t>{2, 2},
        std::vector<std::uint32_t>{11}}) {
    EXPECT_THROW(ct->relight_vertices({"pixel", light}, bad, out), ParameterError);
  }
}

// csr_zstd_vertices against the C++ subset relight on a fresh upload (only the subset's frames
// ever reach the device), and after a full relight (rows outside the subset keep its values).
TEST(CsrZstd, OpenClSubsetKernelMatchesTheCppSubset) {
  ClContext* ctx = default_context();
  if (ctx == nullptr) GTEST_SKIP() << "no OpenCL device";
  for (const TransferMatrix& t : {test_transfer(), wide_transfer()}) {
    SCOPED_TRACE(fmt::format("N = {}", t.cols()));
    const auto ct = compress(t, 3, 24);
    const std::vector<std::uint32_t> subset = t.vertex_count() == 11
                                                  ? std::vector<std::uint32_t>{0, 2, 3, 5, 10}
                                                  : std::vector<std::uint32_t>{1, 3};
    std::vector<bool> in(t.vertex_count(), false);
    for (const std::uint32_t v : subset) in[v] = true;
    const auto m = static_cast<std::size_t>(t.local_count());
    const std::vector<Rgb> first = test_light(t.cols(), 1), second = test_light(t.cols(), 2);
    LocalRadiance cpp;
    ct->relight_vertices({"pixel", second}, subset, cpp);
    for (const bool after_full : {false, true}) {
      SCOPED_TRACE(after_full ? "after a full relight" : "fresh upload");
      auto device = upload_compressed(*ct, *ctx);
      ASSERT_NE(device, nullptr);
      ASSERT_TRUE(device->supports_vertex_subset());
      LocalRadiance before(RadianceBasis::kPixel, t.local_count(), t.vertex_count());
      if (after_full) device->relight({"pixel", first}, before);
      device->set_vertex_subset(subset);
      EXPECT_GT(device->relight_subset_on_device({"pixel", second}), 0.0);
      LocalRadiance gpu = before;
      download(*ctx, device->output_buffer(), std::span<Rgb>(gpu.values), "subset");
      for (std::size_t r = 0; r < gpu.values.size(); ++r) {
        if (in[r / m]) {
          for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(gpu.values[r][c], cpp.values[r][c], 1e-5 * std::abs(cpp.values[r][c]))
                << "row " << r;
        } else if (after_full) {
          EXPECT_EQ(std::memcmp(&gpu.values[r], &before.values[r], sizeof(Rgb)), 0)
              << "row " << r << " outside the subset changed";
        }
      }
    }
  }
}

// A byte flipped or cut off is caught by the archive's checksum; a well-formed archive whose
// frames lie about their contents is caught by load, which decompresses every frame once.
TEST(CsrZstd, CorruptTruncatedOrInconsistentFilesAreInputErrors) {
  const TransferMatrix t = test_transfer();
  prt::testing::TempDir dir("csr_zstd_bad");
  const fs::path file = dir / "t.prt";
  const auto ct = compress(t, 3, 64);
  save_compressed(*ct, file);
  const std::string bytes = [&] {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  auto write_bytes = [&](const std::string& b) {
    std::ofstream(file, std::ios::binary | std::ios::trunc).write(b.data(), b.size());
  };
  std::string flipped = bytes;
  flipped[flipped.size() / 2] ^= 0x04;
  write_bytes(flipped);
  EXPECT_THROW(load_compressed(file), InputError);
  write_bytes(bytes.substr(0, bytes.size() / 3));
  EXPECT_THROW(load_compressed(file), InputError);

  // Re-written through ArchiveWriter, so the checksum is right and only load's checks remain.
  const FramedCsr& good = frames(*ct);
  auto write_archive = [&](const FramedCsr& csr) {
    ArchiveWriter w("compressed-transfer", 1);
    w.add_meta("backend", "csr_zstd");
    w.add_meta("flops_per_relight", 2.0);
    w.add_meta("storage_bytes", 1);
    CsrZstdTransfer(csr).save(w);
    w.write(file);
  };
  write_archive(good);
  EXPECT_NO_THROW(load_compressed(file));
  std::vector<std::pair<std::string, FramedCsr>> bad;
  {
    FramedCsr c = good;
    c.frames[c.frame_offsets[1] + 5] ^= 0xff;  // inside frame 1's compressed data
    bad.emplace_back("a damaged frame", std::move(c));
  }
  {
    FramedCsr c = good;
    c.frame_entries[1] += 1;  // frame 0 decompresses to one entry less than declared
    bad.emplace_back("frame entries that do not match the frames", std::move(c));
  }
  {
    FramedCsr c = good;
    c.frame_offsets.back() -= 1;
    bad.emplace_back("frame offsets short of the frames", std::move(c));
  }
  {
    FramedCsr c = good;
    std::swap(c.frame_offsets[1], c.frame_offsets[2]);
    bad.emplace_back("frame offsets out of order", std::move(c));
  }
  {
    FramedCsr c = good;
    c.supersampling = 1;  // counts above s^2 = 1
    bad.emplace_back("counts above s^2", std::move(c));
  }
  {
    FramedCsr c = good;
    c.block_rows = 32;  // the frame count no longer matches
    bad.emplace_back("another frame size", std::move(c));
  }
  for (const auto& [what, csr] : bad) {
    SCOPED_TRACE(what);
    write_archive(csr);
    try {
      load_compressed(file);
      ADD_FAILURE() << "loaded";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), file);
    }
  }
}

}  // namespace
}  // namespace prt::csr_zstd
