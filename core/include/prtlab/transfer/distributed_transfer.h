#pragma once
// compute_transfer over the ranks of a Communicator (docs/distributed.md): the vertices go out in
// chunks from a WorkQueue, so a rank whose vertices trace slower takes fewer of them (balanced by
// the cost each chunk turns out to have, not by the count), every rank traces with its own
// TransferTracer, and the root assembles the rows in vertex order. A vertex's rows depend on
// nothing but the vertex, so the root's T and SH transfer equal one process's bit for bit.
#include <cstdint>
#include <vector>

#include "prtlab/distributed/communicator.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt {

/// What one rank did in a distributed transfer computation.
struct RankTransferShare {
  int rank = 0;
  std::uint64_t points = 0, chunks = 0;
  double seconds_tracing = 0;    ///< wall time of its chunks (tables included)
  std::uint64_t bytes_sent = 0;  ///< its rows to the root, and the queue's messages
};

struct DistributedTransfer {
  /// On the root: the whole result (stats summed over the ranks, times the root's wall clock);
  /// elsewhere: empty matrices.
  TransferResult result;
  /// On the root: every rank's share, in rank order.
  std::vector<RankTransferShare> shares;
  double seconds_gather = 0;  ///< on the root: receiving and assembling the rows
};

/// Chunks of this many vertices at most (fewer when the mesh is small, so that every rank gets
/// several).
inline constexpr std::size_t kTransferChunk = 2048;

/// Collective over `comm`. With one rank it is compute_transfer(mesh, params).
DistributedTransfer compute_transfer_distributed(const Mesh& mesh, const TransferParams& params,
                                                 Communicator& comm);

/// XXH3-128 hex of T's shape and arrays and of the SH transfer: equal for equal results,
/// whatever the timing stats an archive stores beside them.
std::string transfer_data_checksum(const TransferResult& result);

}  // namespace prt
