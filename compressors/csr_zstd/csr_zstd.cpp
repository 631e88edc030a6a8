#include "csr_zstd/csr_zstd.h"

#include <algorithm>

#include "prtlab/base/error.h"
#include "prtlab/storage/archive.h"

namespace prt::csr_zstd {
namespace {

class CsrZstdCompressor final : public Compressor {
 public:
  CsrZstdCompressor(int level, int block_rows) : level_(level), block_rows_(block_rows) {}

  std::unique_ptr<CompressedTransfer> compress(const TransferInput& input,
                                               Progress& progress) const override {
    check_transfer_shape(input, kName);
    auto out = std::make_unique<CsrZstdTransfer>(
        compress_frames(input.transfer, level_, block_rows_, progress));
    progress.finish();
    return out;
  }

 private:
  int level_, block_rows_;
};

}  // namespace

CsrZstdTransfer::CsrZstdTransfer(FramedCsr csr)
    : csr_(std::make_shared<const FramedCsr>(std::move(csr))),
      decoder_(std::make_shared<const FrameDecoder>()) {}

StorageReport CsrZstdTransfer::storage() const {
  const std::uint64_t frames = csr_->frame_count();
  StorageReport r;
  r.components.push_back(
      {"frames", csr_->frames.size(),
       fmt::format("zstd level {} frames of {} rows, concatenated; each decompresses to the rows' "
                   "u32 row offsets (rows + 1), {} columns and u8 counts",
                   csr_->level, csr_->block_rows, csr_->narrow_columns() ? "u16" : "u32")});
  r.components.push_back({"frame_offsets", (frames + 1) * 8,
                          "u64 per frame + 1: byte offset of each frame in frames, last = size"});
  r.components.push_back({"frame_entries", (frames + 1) * 4,
                          "u32 per frame + 1: index of the frame's first entry in T, last = nnz"});
  r.components.push_back(
      {"scale", 4, "f32 once: the value of a count of 1, 1/s^2 (stored as s in the metadata)"});
  return r;
}

LightCoeffs CsrZstdTransfer::project_light(const Cubemap& radiance) const {
  return pixel_light(radiance, static_cast<std::size_t>(csr_->pixel_count), kName);
}

std::unique_ptr<DeviceRelighter> CsrZstdTransfer::upload(ClContext& context,
                                                         const ParamSet&) const {
  return upload_frames(context, csr_);
}

void CsrZstdTransfer::save(ArchiveWriter& archive) const {
  archive.add_meta("csr_zstd_version", kStateVersion);
  archive.add_meta("vertices", csr_->vertices);
  archive.add_meta("local_count", csr_->local_count);
  archive.add_meta("pixel_count", csr_->pixel_count);
  archive.add_meta("supersampling", csr_->supersampling);
  archive.add_meta("block_rows", csr_->block_rows);
  archive.add_meta("level", csr_->level);
  archive.add_section("frames", csr_->frames);
  archive.add_section("frame_offsets", csr_->frame_offsets);
  archive.add_section("frame_entries", csr_->frame_entries);
}

std::unique_ptr<CompressedTransfer> CsrZstdTransfer::load(const ArchiveReader& r) {
  const auto fail = [&](const std::string& problem) {
    return InputError(r.path(), fmt::format("{}: {}", kName, problem));
  };
  const int version = r.meta_value<int>("csr_zstd_version");
  if (version != kStateVersion)
    throw fail(fmt::format("state version {} is not the version {} this build reads", version,
                           kStateVersion));
  FramedCsr csr;
  csr.vertices = r.meta_value<std::size_t>("vertices");
  csr.local_count = r.meta_value<int>("local_count");
  csr.pixel_count = r.meta_value<int>("pixel_count");
  csr.supersampling = r.meta_value<int>("supersampling");
  csr.block_rows = r.meta_value<int>("block_rows");
  csr.level = r.meta_value<int>("level");
  if (csr.local_count <= 0 || csr.pixel_count <= 0 || csr.supersampling <= 0 || csr.block_rows <= 0)
    throw fail(fmt::format("bad shape: M = {}, N = {}, s = {}, block_rows = {}", csr.local_count,
                           csr.pixel_count, csr.supersampling, csr.block_rows));
  const std::size_t frames = (csr.rows() + csr.block_rows - 1) / csr.block_rows;
  csr.frames = r.section<std::uint8_t>("frames");
  csr.frame_offsets = r.section<std::uint64_t>("frame_offsets", frames + 1);
  csr.frame_entries = r.section<std::uint32_t>("frame_entries", frames + 1);
  // Everything decode() trusts (frame bounds, sizes) before it runs.
  if (csr.frame_offsets.front() != 0 ||
      !std::is_sorted(csr.frame_offsets.begin(), csr.frame_offsets.end()) ||
      csr.frame_offsets.back() != csr.frames.size())
    throw fail("frame offsets do not rise from 0 to the size of the frames");
  if (csr.frame_entries.front() != 0 ||
      !std::is_sorted(csr.frame_entries.begin(), csr.frame_entries.end()))
    throw fail("frame entries do not rise from 0");
  // Decompressing every frame once checks what the kernel trusts: each frame's size, its row
  // offsets against its entries, and T's invariants (columns in range, counts in 1..s^2).
  try {
    (void)decompress_all(csr);
  } catch (const ParameterError& e) {
    throw fail(e.what());
  }
  return std::make_unique<CsrZstdTransfer>(std::move(csr));
}

CompressorEntry registry_entry() {
  CompressorEntry e;
  e.name = std::string(kName);
  e.description =
      "baseline: the exact CSR (row offsets, columns, u8 counts) compressed with zstd in frames "
      "of block_rows rows, all decompressed at every relight (lossless)";
  e.params = {
      {"level",
       ParamType::kInt,
       "3",
       1.0,
       19.0,
       {},
       "zstd compression level (higher: smaller frames, slower compression)"},
      {"block_rows",
       ParamType::kInt,
       "1024",
       1.0,
       1048576.0,
       {},
       "rows of T per independently compressed zstd frame (the unit of parallel decompression)"},
  };
  e.size_knob = SizeKnob{.key = "level", .direction = SizeKnob::Direction::kLargerIsLessStorage};
  e.lossless = true;
  e.cost_hint_seconds = 0.3;  // where it was measured: docs/cli.md, "Cost hints"
  e.create = [](const ParamSet& p) -> std::unique_ptr<Compressor> {
    return std::make_unique<CsrZstdCompressor>(static_cast<int>(p.get_int("level")),
                                               static_cast<int>(p.get_int("block_rows")));
  };
  e.load = &CsrZstdTransfer::load;
  return e;
}

PRT_REGISTER_COMPRESSOR(registry_entry);

}  // namespace prt::csr_zstd
