#pragma once
// Items computed once over all ranks and then known to every rank: a work queue hands the items
// out, every thread of every rank takes them one at a time (a slow item holds up only its
// thread), each item's result is a message, and every rank ends with all the messages. What a
// backend splits over the ranks of a collective compression (bicluster's row groups, srbf_cta's
// cluster refits) goes through here, so that all ranks continue with the one-process state.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/distributed/communicator.h"

namespace prt {

/// Thrown on every rank but the failing one when a work item failed (that rank rethrows the
/// item's own exception): every rank leaves compute_on_all_ranks together.
class CollectiveError : public Error {
 public:
  using Error::Error;
};

/// Runs work(i, out) for every item i in [0, count) on some thread of some rank; `out` starts
/// empty, and what work() appends to it is item i's message (it should name i: the messages
/// arrive in no particular order). Returns every message, concatenated, on every rank.
/// Collective over `comm`; threads from the calling rank's TBB arena. When an item throws, the
/// other items still run, and then the call throws on every rank: the item's exception where
/// it failed, CollectiveError elsewhere.
std::vector<std::uint8_t> compute_on_all_ranks(
    Communicator& comm, std::size_t count,
    const std::function<void(std::size_t, std::vector<std::uint8_t>&)>& work);

}  // namespace prt
