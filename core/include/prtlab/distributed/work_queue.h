#pragma once
// Dynamic load balancing over a communicator: the items 0 .. count-1 go, in order, to whichever
// rank asks next, so a slow item holds up only the rank that took it. The root hands them out
// from a thread of its own while it works on items too. Collective: every rank constructs the
// queue and calls next() until it returns nothing.
#include <atomic>
#include <cstddef>
#include <memory>
#include <optional>
#include <thread>

#include "prtlab/distributed/communicator.h"

namespace prt {

class WorkQueue {
 public:
  WorkQueue(Communicator& comm, std::size_t count);
  ~WorkQueue();
  WorkQueue(const WorkQueue&) = delete;
  WorkQueue& operator=(const WorkQueue&) = delete;

  /// The next item for this rank, or nothing when every item is taken.
  std::optional<std::size_t> next();
  /// Items this rank took.
  std::size_t taken() const { return taken_; }

 private:
  void serve();
  Communicator& comm_;
  std::size_t count_;
  int tag_ = 0;
  std::atomic<std::size_t> cursor_{0};
  std::size_t taken_ = 0;
  std::thread server_;
};

}  // namespace prt
