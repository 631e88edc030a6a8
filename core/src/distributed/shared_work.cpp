#include "prtlab/distributed/shared_work.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <exception>
#include <mutex>
#include <optional>

#include "prtlab/base/error.h"
#include "prtlab/distributed/work_queue.h"

namespace prt {

std::vector<std::uint8_t> compute_on_all_ranks(
    Communicator& comm, std::size_t count,
    const std::function<void(std::size_t, std::vector<std::uint8_t>&)>& work) {
  std::vector<std::uint8_t> mine;
  std::exception_ptr failure;
  {
    WorkQueue queue(comm, count);
    std::mutex lock;  // the queue is not thread-safe, and `mine` is shared
    const int workers = tbb::this_task_arena::max_concurrency();
    tbb::parallel_for(0, workers, [&](int) {
      for (;;) {
        std::optional<std::size_t> i;
        {
          const std::lock_guard hold(lock);
          i = queue.next();
        }
        if (!i) return;
        std::vector<std::uint8_t> out;
        try {
          // Isolated: a thread waiting inside the item's own parallel loops must not take up
          // another item (that loop runs until the queue is empty) before it finishes this one.
          tbb::this_task_arena::isolate([&] { work(*i, out); });
        } catch (...) {
          // The queue is still drained, so that every rank reaches the exchange below.
          const std::lock_guard hold(lock);
          if (!failure) failure = std::current_exception();
          continue;
        }
        const std::lock_guard hold(lock);
        mine.insert(mine.end(), out.begin(), out.end());
      }
    });
  }
  // An item that failed fails the call on every rank, so that all leave it together.
  if (comm.any(failure != nullptr)) {
    if (failure) std::rethrow_exception(failure);
    throw CollectiveError(fmt::format(
        "a work item failed on another of the {} ranks (its error is printed there)", comm.size()));
  }
  std::vector<std::uint8_t> all;
  for (const auto& bytes : comm.gather(mine)) all.insert(all.end(), bytes.begin(), bytes.end());
  return comm.broadcast(std::move(all));
}

}  // namespace prt
