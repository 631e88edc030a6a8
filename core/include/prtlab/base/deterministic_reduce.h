#pragma once
// Parallel reductions whose result does not depend on the thread count, the scheduler or the
// number of MPI ranks: the range is cut into blocks of a fixed size, each block is reduced
// sequentially, and the block results are combined in block order on the calling thread. A
// floating-point sum regrouped by however TBB happened to split the range (parallel_reduce,
// combinable) differs in its last digits between runs, which breaks every bit-for-bit comparison
// (one process against several ranks, one thread against two).
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include <cstddef>
#include <utility>
#include <vector>

namespace prt {

/// Reduces [0, n) in blocks of `block` indices: `reduce_block(begin, end)` returns the value of
/// one block (computed sequentially inside it), `combine(acc, value)` folds the block values into
/// `init` in block order. The same n and block give the same result bit for bit on any number of
/// threads.
template <class T, class BlockFn, class CombineFn>
T deterministic_reduce(std::size_t n, std::size_t block, T init, BlockFn&& reduce_block,
                       CombineFn&& combine) {
  if (block == 0) block = 1;
  const std::size_t blocks = (n + block - 1) / block;
  std::vector<T> partial(blocks);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, blocks, 1),
      [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
          const std::size_t begin = b * block;
          const std::size_t end = begin + block < n ? begin + block : n;
          partial[b] = reduce_block(begin, end);
        }
      },
      tbb::simple_partitioner());
  for (T& p : partial) init = combine(std::move(init), std::move(p));
  return init;
}

/// The sum over [0, n) of `value_of_block(begin, end)`, blocks of `block` indices, summed in
/// block order: deterministic for any thread count.
template <class BlockFn>
double deterministic_sum(std::size_t n, std::size_t block, BlockFn&& value_of_block) {
  return deterministic_reduce(n, block, 0.0, std::forward<BlockFn>(value_of_block),
                              [](double a, double b) { return a + b; });
}

}  // namespace prt
