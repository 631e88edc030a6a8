// The zstd frames of backend `csr_zstd`: compression of T's CSR arrays in blocks of rows, and
// their decompression into per-thread scratch buffers.
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>

#include "csr_zstd/csr_zstd.h"
#include "prtlab/base/error.h"

namespace prt::csr_zstd {
namespace {

struct CctxDeleter {
  void operator()(ZSTD_CCtx* c) const { ZSTD_freeCCtx(c); }
};
struct DctxDeleter {
  void operator()(ZSTD_DCtx* d) const { ZSTD_freeDCtx(d); }
};

// One frame's arrays back to back: the layout FramedCsr documents.
std::vector<std::uint8_t> raw_frame(const TransferMatrix& t, std::size_t r0, std::size_t r1) {
  const auto offsets = t.row_offsets();
  const std::uint32_t e0 = offsets[r0], e1 = offsets[r1];
  const std::size_t n = e1 - e0;
  const std::size_t column_bytes = t.narrow_columns() ? 2 : 4;
  std::vector<std::uint8_t> raw(4 * (r1 - r0 + 1) + (column_bytes + 1) * n);
  std::uint8_t* p = raw.data();
  std::memcpy(p, offsets.data() + r0, 4 * (r1 - r0 + 1));
  p += 4 * (r1 - r0 + 1);
  // An empty T has null column and count arrays: memcpy must not see them, even for 0 bytes.
  if (n == 0) return raw;
  if (t.narrow_columns()) {
    std::memcpy(p, t.columns16().data() + e0, 2 * n);
  } else {
    std::memcpy(p, t.columns32().data() + e0, 4 * n);
  }
  p += column_bytes * n;
  std::memcpy(p, t.counts().data() + e0, n);
  return raw;
}

}  // namespace

std::size_t FramedCsr::frame_row_end(std::size_t f) const {
  return std::min(rows(), (f + 1) * static_cast<std::size_t>(block_rows));
}

std::size_t FramedCsr::frame_raw_bytes(std::size_t f) const {
  const std::size_t frame_rows = frame_row_end(f) - frame_row_begin(f);
  const std::size_t entries = frame_entries[f + 1] - frame_entries[f];
  return 4 * (frame_rows + 1) + (column_bytes() + 1) * entries;
}

FramedCsr compress_frames(const TransferMatrix& t, int level, int block_rows, Progress& progress) {
  PRT_CHECK(block_rows > 0, "block_rows {} must be positive", block_rows);
  FramedCsr csr;
  csr.vertices = t.vertex_count();
  csr.local_count = t.local_count();
  csr.pixel_count = static_cast<int>(t.cols());
  csr.supersampling = t.supersampling();
  csr.block_rows = block_rows;
  csr.level = level;
  const std::size_t frames = (t.rows() + block_rows - 1) / block_rows;
  std::vector<std::uint32_t> entries(frames + 1);
  for (std::size_t f = 0; f < frames; ++f)
    entries[f] = t.row_offsets()[f * static_cast<std::size_t>(block_rows)];
  entries[frames] = static_cast<std::uint32_t>(t.nnz());
  csr.frame_entries = std::move(entries);

  std::vector<std::vector<std::uint8_t>> compressed(frames);
  tbb::enumerable_thread_specific<std::unique_ptr<ZSTD_CCtx, CctxDeleter>> contexts(
      [] { return std::unique_ptr<ZSTD_CCtx, CctxDeleter>(ZSTD_createCCtx()); });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, frames, 1), [&](const auto& range) {
    ZSTD_CCtx* cctx = contexts.local().get();
    PRT_CHECK(cctx != nullptr, "zstd: out of memory creating a compression context");
    for (std::size_t f = range.begin(); f != range.end(); ++f) {
      const std::size_t r0 = csr.frame_row_begin(f), r1 = csr.frame_row_end(f);
      const std::vector<std::uint8_t> raw = raw_frame(t, r0, r1);
      std::vector<std::uint8_t>& out = compressed[f];
      out.resize(ZSTD_compressBound(raw.size()));
      // Each call sets the level anew: a context keeps no state between frames, so the bytes
      // are the same whichever thread compresses which frame.
      const std::size_t n =
          ZSTD_compressCCtx(cctx, out.data(), out.size(), raw.data(), raw.size(), level);
      PRT_CHECK(!ZSTD_isError(n), "zstd compression of frame {} failed: {}", f,
                ZSTD_getErrorName(n));
      out.resize(n);
      progress.advance(static_cast<std::int64_t>(r1 - r0));
    }
  });
  std::vector<std::uint64_t> offsets(frames + 1, 0);
  for (std::size_t f = 0; f < frames; ++f) offsets[f + 1] = offsets[f] + compressed[f].size();
  csr.frame_offsets = std::move(offsets);
  csr.frames.resize(csr.frame_offsets[frames]);
  for (std::size_t f = 0; f < frames; ++f)
    std::copy(compressed[f].begin(), compressed[f].end(),
              csr.frames.begin() + static_cast<std::ptrdiff_t>(csr.frame_offsets[f]));
  return csr;
}

struct FrameDecoder::Impl {
  struct PerThread {
    std::unique_ptr<ZSTD_DCtx, DctxDeleter> context{ZSTD_createDCtx()};
    // u32 elements keep the row offsets and u32 columns of the frame aligned.
    std::vector<std::uint32_t> scratch;
  };
  mutable tbb::enumerable_thread_specific<PerThread> threads;
};

FrameDecoder::FrameDecoder() : impl_(std::make_unique<Impl>()) {}
FrameDecoder::~FrameDecoder() = default;

FrameView FrameDecoder::decode(const FramedCsr& csr, std::size_t f) const {
  Impl::PerThread& local = impl_->threads.local();
  PRT_CHECK(local.context != nullptr, "zstd: out of memory creating a decompression context");
  const std::size_t raw_bytes = csr.frame_raw_bytes(f);
  local.scratch.resize((raw_bytes + 3) / 4);
  auto* dst = reinterpret_cast<std::uint8_t*>(local.scratch.data());
  const std::uint64_t begin = csr.frame_offsets[f], end = csr.frame_offsets[f + 1];
  const std::size_t n = ZSTD_decompressDCtx(local.context.get(), dst, raw_bytes,
                                            csr.frames.data() + begin, end - begin);
  if (ZSTD_isError(n))
    throw ParameterError(
        fmt::format("{}: frame {} does not decompress: {}", kName, f, ZSTD_getErrorName(n)));
  if (n != raw_bytes)
    throw ParameterError(
        fmt::format("{}: frame {} decompresses to {} bytes, its rows and entries "
                    "need {}",
                    kName, f, n, raw_bytes));
  FrameView v;
  v.row_begin = csr.frame_row_begin(f);
  v.row_end = csr.frame_row_end(f);
  v.entry_begin = csr.frame_entries[f];
  v.entry_end = csr.frame_entries[f + 1];
  v.offsets = local.scratch.data();
  const std::size_t frame_rows = v.row_end - v.row_begin;
  if (v.offsets[0] != v.entry_begin || v.offsets[frame_rows] != v.entry_end)
    throw ParameterError(
        fmt::format("{}: frame {} holds row offsets {}..{}, its entries are {}..{}", kName, f,
                    v.offsets[0], v.offsets[frame_rows], v.entry_begin, v.entry_end));
  const std::uint8_t* columns = dst + 4 * (frame_rows + 1);
  const std::size_t entries = v.entry_end - v.entry_begin;
  if (csr.narrow_columns()) {
    v.columns16 = reinterpret_cast<const std::uint16_t*>(columns);
  } else {
    v.columns32 = reinterpret_cast<const std::uint32_t*>(columns);
  }
  v.counts = columns + csr.column_bytes() * entries;
  return v;
}

TransferMatrix decompress_all(const FramedCsr& csr) {
  const FrameDecoder decoder;
  std::vector<std::uint32_t> offsets(csr.rows() + 1, 0);
  std::vector<std::uint32_t> columns(csr.nnz());
  std::vector<std::uint8_t> counts(csr.nnz());
  for (std::size_t f = 0; f < csr.frame_count(); ++f) {
    const FrameView v = decoder.decode(csr, f);
    const std::size_t entries = v.entry_end - v.entry_begin;
    std::copy(v.offsets, v.offsets + (v.row_end - v.row_begin + 1),
              offsets.begin() + static_cast<std::ptrdiff_t>(v.row_begin));
    for (std::size_t i = 0; i < entries; ++i)
      columns[v.entry_begin + i] = v.columns16 ? v.columns16[i] : v.columns32[i];
    std::copy(v.counts, v.counts + entries, counts.begin() + v.entry_begin);
  }
  return TransferMatrix::from_csr(csr.vertices, csr.local_count, csr.pixel_count, csr.supersampling,
                                  std::move(offsets), columns, std::move(counts));
}

}  // namespace prt::csr_zstd
