#include "prtlab/distributed/shared_work.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <mutex>
#include <optional>

#include "prtlab/distributed/work_queue.h"

namespace prt {

std::vector<std::uint8_t> compute_on_all_ranks(
    Communicator& comm, std::size_t count,
    const std::function<void(std::size_t, std::vector<std::uint8_t>&)>& work) {
  std::vector<std::uint8_t> mine;
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
        work(*i, out);
        const std::lock_guard hold(lock);
        mine.insert(mine.end(), out.begin(), out.end());
      }
    });
  }
  std::vector<std::uint8_t> all;
  for (const auto& bytes : comm.gather(mine)) all.insert(all.end(), bytes.begin(), bytes.end());
  return comm.broadcast(std::move(all));
}

}  // namespace prt
