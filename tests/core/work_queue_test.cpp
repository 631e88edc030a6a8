// The distributed subsystem on one process (what every run without mpirun uses): the work queue
// hands out every item once, in order, and the collectives are the identity. Several ranks are
// tested by tests/mpi/ranks_test.sh (CTest mpi.ranks) in a build with MPI.
#include "prtlab/distributed/work_queue.h"

#include <gtest/gtest.h>

#include <cstdlib>

#include "prtlab/base/error.h"

namespace prt {
namespace {

TEST(WorkQueue, OneProcessTakesEveryItemOnceInOrder) {
  Communicator& world = Communicator::world();
  ASSERT_FALSE(world.distributed());
  for (std::size_t count : {0u, 1u, 17u}) {
    WorkQueue q(world, count);
    std::vector<std::size_t> got;
    while (const auto i = q.next()) got.push_back(*i);
    ASSERT_EQ(got.size(), count);
    for (std::size_t i = 0; i < count; ++i) EXPECT_EQ(got[i], i);
    EXPECT_FALSE(q.next()) << "asking again after the end";
    EXPECT_EQ(q.taken(), count);
  }
}

TEST(Communicator, OneProcessCollectivesAreTheIdentity) {
  Communicator& world = Communicator::world();
  EXPECT_EQ(world.rank(), 0);
  EXPECT_EQ(world.size(), 1);
  EXPECT_TRUE(world.is_root());
  const std::vector<std::uint8_t> bytes = {1, 2, 3};
  EXPECT_EQ(world.broadcast(bytes), bytes);
  const auto all = world.gather(bytes);
  ASSERT_EQ(all.size(), 1u);
  EXPECT_EQ(all[0], bytes);
  EXPECT_TRUE(world.any(true));
  EXPECT_FALSE(world.any(false));
  EXPECT_EQ(world.description(), "1 process");
  const int a = world.fresh_tag(), b = world.fresh_tag();
  EXPECT_NE(a, b);
}

TEST(Communicator, AProcessLaunchedAsOneOfSeveralRanksIsNotMistakenForOne) {
  // What the session reads from the environment an MPI starter sets.
  EXPECT_FALSE(launched_by_mpi());
  ::setenv("OMPI_COMM_WORLD_SIZE", "4", 1);
  EXPECT_TRUE(launched_by_mpi());
  ::unsetenv("OMPI_COMM_WORLD_SIZE");
  ::setenv("PMIX_RANK", "0", 1);
  EXPECT_TRUE(launched_by_mpi());
  ::unsetenv("PMIX_RANK");
  EXPECT_FALSE(launched_by_mpi());
}

}  // namespace
}  // namespace prt
