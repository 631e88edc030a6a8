#include "prtlab/transfer/distributed_transfer.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <map>

#include "prtlab/base/error.h"
#include "prtlab/base/progress.h"
#include "prtlab/base/statistics.h"
#include "prtlab/distributed/byte_stream.h"
#include "prtlab/distributed/work_queue.h"
#include "prtlab/sphere/cubemap.h"
#include "prtlab/storage/content_hash.h"

namespace prt {
namespace {

struct Chunk {
  std::vector<std::uint32_t> offsets, columns;
  std::vector<std::uint8_t> counts;
  std::vector<double> sh;
};

}  // namespace

std::string transfer_data_checksum(const TransferResult& r) {
  const TransferMatrix& t = r.transfer;
  Hasher h;
  h.add("prtlab-transfer-data")
      .add(static_cast<std::uint64_t>(t.vertex_count()))
      .add(t.local_count())
      .add(static_cast<std::uint64_t>(t.cols()))
      .add(t.supersampling());
  h.add_array(t.row_offsets());
  if (t.narrow_columns())
    h.add_array(t.columns16());
  else
    h.add_array(t.columns32());
  h.add_array(t.counts());
  h.add(r.sh ? r.sh->order() : 0);
  if (r.sh) h.add(std::as_bytes(r.sh->data()));
  return h.digest().hex();
}

DistributedTransfer compute_transfer_distributed(const Mesh& mesh, const TransferParams& params,
                                                 Communicator& comm) {
  DistributedTransfer out;
  if (!comm.distributed()) {
    out.result = compute_transfer(mesh, params);
    out.shares.push_back({0, out.result.stats.points, 1, out.result.stats.seconds_total, 0});
    return out;
  }
  const auto t_start = std::chrono::steady_clock::now();
  const std::vector<SurfacePoint> points = vertex_points(mesh);
  const std::size_t ranks = static_cast<std::size_t>(comm.size());
  const std::size_t chunk = std::clamp<std::size_t>(points.size() / (ranks * 8), 1, kTransferChunk);
  const std::size_t chunks = (points.size() + chunk - 1) / chunk;
  const std::uint64_t sent_before = comm.bytes_sent();

  TransferParams quiet = params;
  quiet.show_progress = false;
  const TransferTracer tracer(mesh, quiet);
  // The root's bar follows its own chunks: the others work at the same time.
  Progress progress(fmt::format("transfer (rank 0 of {})", ranks),
                    static_cast<std::int64_t>(chunks), params.show_progress && comm.is_root());
  std::vector<std::uint8_t> message;
  ByteWriter w(message);
  std::vector<std::uint64_t> taken;
  TransferStats sum;
  {
    WorkQueue queue(comm, chunks);
    while (const auto c = queue.next()) {
      const std::size_t first = *c * chunk, count = std::min(chunk, points.size() - first);
      const TransferResult part =
          tracer.compute(std::span<const SurfacePoint>(points).subspan(first, count));
      const TransferMatrix& t = part.transfer;
      w.put<std::uint64_t>(*c);
      w.put_array(t.row_offsets());
      std::vector<std::uint32_t> cols(t.nnz());
      for (std::size_t i = 0; i < cols.size(); ++i) cols[i] = t.column(i);
      w.put_array(std::span<const std::uint32_t>(cols));
      w.put_array(t.counts());
      w.put_array(part.sh ? part.sh->data() : std::span<const double>());
      taken.push_back(*c);
      sum.subrays += part.stats.subrays;
      sum.rays_traced += part.stats.rays_traced;
      sum.rays_unblocked += part.stats.rays_unblocked;
      sum.horizon_lifted += part.stats.horizon_lifted;
      sum.thread_seconds_trace += part.stats.thread_seconds_trace;
      sum.thread_seconds_bin += part.stats.thread_seconds_bin;
      sum.thread_seconds_sh += part.stats.thread_seconds_sh;
      sum.threads = part.stats.threads;
      progress.advance(1);
    }
  }
  progress.finish();
  const double seconds_tracing = seconds_since(t_start);
  // The rank's totals follow its chunks; the last 8 bytes say how long they are.
  std::vector<std::uint8_t> trailer;
  ByteWriter tw(trailer);
  tw.put<std::uint64_t>(taken.size());
  tw.put(sum.subrays);
  tw.put(sum.rays_traced);
  tw.put(sum.rays_unblocked);
  tw.put(sum.horizon_lifted);
  tw.put(sum.thread_seconds_trace);
  tw.put(sum.thread_seconds_bin);
  tw.put(sum.thread_seconds_sh);
  tw.put(sum.threads);
  tw.put(seconds_tracing);
  tw.put<std::uint64_t>(comm.bytes_sent() - sent_before);  // the queue's messages
  message.insert(message.end(), trailer.begin(), trailer.end());
  w.put<std::uint64_t>(trailer.size());

  const auto t_gather = std::chrono::steady_clock::now();
  const auto all = comm.gather(message);
  if (!comm.is_root()) return out;

  std::map<std::uint64_t, Chunk> by_index;
  TransferStats& stats = out.result.stats;
  stats.points = points.size();
  stats.ranks = comm.size();
  for (std::size_t r = 0; r < all.size(); ++r) {
    const auto& bytes = all[r];
    PRT_CHECK(bytes.size() >= sizeof(std::uint64_t), "distributed transfer: rank {} sent nothing",
              r);
    std::uint64_t trailer_size = 0;
    std::memcpy(&trailer_size, bytes.data() + bytes.size() - sizeof trailer_size,
                sizeof trailer_size);
    PRT_CHECK(trailer_size <= bytes.size() - sizeof trailer_size,
              "distributed transfer: rank {}'s message is corrupt", r);
    const std::size_t body = bytes.size() - sizeof trailer_size - trailer_size;
    ByteReader tail(std::span<const std::uint8_t>(bytes).subspan(body, trailer_size),
                    "distributed transfer");
    const auto n = tail.get<std::uint64_t>();
    RankTransferShare share;
    share.rank = static_cast<int>(r);
    share.chunks = n;
    stats.subrays += tail.get<std::uint64_t>();
    stats.rays_traced += tail.get<std::uint64_t>();
    stats.rays_unblocked += tail.get<std::uint64_t>();
    stats.horizon_lifted += tail.get<std::uint64_t>();
    stats.thread_seconds_trace += tail.get<double>();
    stats.thread_seconds_bin += tail.get<double>();
    stats.thread_seconds_sh += tail.get<double>();
    stats.threads += tail.get<int>();
    share.seconds_tracing = tail.get<double>();
    share.bytes_sent = tail.get<std::uint64_t>() + (r == 0 ? 0 : bytes.size());
    ByteReader in(std::span<const std::uint8_t>(bytes).first(body), "distributed transfer");
    for (std::uint64_t k = 0; k < n; ++k) {
      const auto index = in.get<std::uint64_t>();
      Chunk c;
      c.offsets = in.get_array<std::uint32_t>();
      c.columns = in.get_array<std::uint32_t>();
      c.counts = in.get_array<std::uint8_t>();
      c.sh = in.get_array<double>();
      share.points += std::min(chunk, points.size() - index * chunk);
      PRT_CHECK(by_index.emplace(index, std::move(c)).second,
                "distributed transfer: chunk {} came twice", index);
    }
    out.shares.push_back(share);
  }
  PRT_CHECK(by_index.size() == chunks, "distributed transfer: {} of {} chunks arrived",
            by_index.size(), chunks);
  const int m = params.local_grid * params.local_grid;
  std::vector<std::uint32_t> offsets{0}, columns;
  std::vector<std::uint8_t> counts;
  offsets.reserve(points.size() * static_cast<std::size_t>(m) + 1);
  std::vector<double> sh;
  for (auto& [index, c] : by_index) {
    const std::uint32_t base = offsets.back();
    for (std::size_t i = 1; i < c.offsets.size(); ++i) offsets.push_back(base + c.offsets[i]);
    columns.insert(columns.end(), c.columns.begin(), c.columns.end());
    counts.insert(counts.end(), c.counts.begin(), c.counts.end());
    sh.insert(sh.end(), c.sh.begin(), c.sh.end());
    c = Chunk{};
  }
  out.result.transfer = TransferMatrix::from_csr(
      points.size(), m, CubemapLayout(params.cubemap_resolution).pixel_count(),
      params.supersampling, std::move(offsets), columns, std::move(counts));
  if (params.sh_order > 0) {
    out.result.sh.emplace(params.sh_order, points.size());
    PRT_CHECK(sh.size() == out.result.sh->data().size(),
              "distributed transfer: {} SH values for {}", sh.size(), out.result.sh->data().size());
    std::copy(sh.begin(), sh.end(), out.result.sh->mutable_data().begin());
  }
  out.seconds_gather = seconds_since(t_gather);
  stats.seconds_total = seconds_since(t_start);
  stats.seconds_points = seconds_tracing;
  stats.seconds_assemble = out.seconds_gather;
  return out;
}

}  // namespace prt
