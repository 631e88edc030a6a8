#include "prtlab/distributed/work_queue.h"

#include <chrono>
#include <cstring>
#include <limits>
#include <vector>

namespace prt {
namespace {

constexpr std::uint64_t kNoMore = std::numeric_limits<std::uint64_t>::max();
// How long the root's server sleeps between looks for a request: short beside any item, and
// it keeps the server off a core it would otherwise spin on.
constexpr auto kPoll = std::chrono::microseconds(200);

std::vector<std::uint8_t> encode(std::uint64_t x) {
  std::vector<std::uint8_t> b(sizeof x);
  std::memcpy(b.data(), &x, sizeof x);
  return b;
}

}  // namespace

WorkQueue::WorkQueue(Communicator& comm, std::size_t count) : comm_(comm), count_(count) {
  if (!comm_.distributed()) return;
  tag_ = comm_.fresh_tag();
  if (comm_.is_root()) server_ = std::thread([this] { serve(); });
}

WorkQueue::~WorkQueue() {
  if (server_.joinable()) server_.join();
}

void WorkQueue::serve() {
  int finished = 0;
  const int remote = comm_.size() - 1;
  std::vector<std::uint8_t> request;
  while (finished < remote) {
    int from = -1;
    if (!comm_.try_receive(tag_, from, request)) {
      std::this_thread::sleep_for(kPoll);
      continue;
    }
    const std::size_t i = cursor_.fetch_add(1);
    if (i >= count_) ++finished;
    comm_.send(from, tag_, encode(i < count_ ? i : kNoMore));
  }
}

std::optional<std::size_t> WorkQueue::next() {
  if (!comm_.distributed() || comm_.is_root()) {
    if (cursor_.load() >= count_) return std::nullopt;
    const std::size_t i = cursor_.fetch_add(1);
    if (i >= count_) return std::nullopt;
    ++taken_;
    return i;
  }
  if (cursor_.load() == kNoMore) return std::nullopt;  // told already: ask no more
  comm_.send(0, tag_, encode(0));
  const auto reply = comm_.receive(0, tag_);
  std::uint64_t i = kNoMore;
  if (reply.size() == sizeof i) std::memcpy(&i, reply.data(), sizeof i);
  if (i == kNoMore) {
    cursor_.store(kNoMore);
    return std::nullopt;
  }
  ++taken_;
  return static_cast<std::size_t>(i);
}

}  // namespace prt
