// Backend `bicluster`, grouped search (bicluster_search.h, SearchOptions): group boundaries fall
// on whole vertices and balance the non-zeros, every group count reconstructs T exactly, the
// result depends on (seed, groups) and not on the thread count, and merge_identical joins only
// biclusters it may join (identical columns and constants, disjoint rows).
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <random>

#include "bicluster/bicluster.h"
#include "bicluster/bicluster_search.h"
#include "prtlab/transfer/random_transfer.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt::bicluster {
namespace {

SparseCounts random_t(std::uint64_t seed, std::size_t vertices, double density = 0.5) {
  return counts_of(random_transfer(seed, RandomTransferSpec{vertices, 3, 3, 2, density, {2}}));
}

TEST(BiclusterGroups, BoundsAreWholeVerticesAndBalanceTheNonZeros) {
  const SparseCounts t = random_t(3, 50);
  const std::size_t m = 9;
  for (int groups : {1, 2, 3, 7, 50, 80}) {
    SCOPED_TRACE(::testing::Message() << groups << " groups");
    const auto bounds = group_bounds(t, m, groups);
    ASSERT_EQ(bounds.size(), static_cast<std::size_t>(groups) + 1);
    EXPECT_EQ(bounds.front(), 0u);
    EXPECT_EQ(bounds.back(), t.rows);
    for (std::size_t g = 0; g + 1 < bounds.size(); ++g) {
      EXPECT_LE(bounds[g], bounds[g + 1]);
      EXPECT_EQ(bounds[g] % m, 0u) << "boundary " << g << " cuts a vertex";
    }
    if (groups <= 7) {
      // Each group holds its share of the non-zeros to within one vertex (of at most M * N / 2
      // entries here... in practice far fewer).
      const double share = static_cast<double>(t.nnz()) / groups;
      std::size_t max_vertex = 0;
      for (std::size_t v = 0; v < 50; ++v)
        max_vertex = std::max<std::size_t>(max_vertex, t.offsets[(v + 1) * m] - t.offsets[v * m]);
      for (std::size_t g = 0; g + 1 < bounds.size(); ++g) {
        const double held = t.offsets[bounds[g + 1]] - t.offsets[bounds[g]];
        EXPECT_NEAR(held, share, 2.0 * static_cast<double>(max_vertex)) << "group " << g;
      }
    }
  }
}

TEST(BiclusterGroups, EveryGroupCountReconstructsExactly) {
  const SparseCounts t = random_t(9, 40);
  std::int64_t one_group_cost = 0;
  for (int groups : {1, 2, 3, 5, 16, 64}) {
    SCOPED_TRACE(::testing::Message() << groups << " groups");
    const Biclustering b = search(t, SearchOptions{7, groups, 9}, Progress::null());
    EXPECT_EQ(b.reconstruct(), t);
    EXPECT_LE(b.cost(), 2 * static_cast<std::int64_t>(t.nnz()));
    if (groups == 1) one_group_cost = b.cost();
    for (const Bicluster& bc : b.biclusters) {
      EXPECT_TRUE(std::is_sorted(bc.rows.begin(), bc.rows.end()));
      EXPECT_TRUE(std::adjacent_find(bc.rows.begin(), bc.rows.end()) == bc.rows.end());
    }
  }
  EXPECT_GT(one_group_cost, 0);
}

TEST(BiclusterGroups, OneGroupIsThePlainSearchMerged) {
  const SparseCounts t = random_t(4, 30);
  Biclustering plain = search(t, 11, Progress::null());
  merge_identical(plain);
  EXPECT_EQ(search(t, SearchOptions{11, 1, 9}, Progress::null()), plain);
  EXPECT_EQ(group_seed(11, 0), 11u);
  EXPECT_NE(group_seed(11, 1), group_seed(11, 2));
  EXPECT_NE(group_seed(11, 1), group_seed(12, 1));
}

TEST(BiclusterGroups, ResultDoesNotDependOnTheThreadCount) {
  const SparseCounts t = random_t(6, 60);
  const SearchOptions options{3, 6, 9};
  Biclustering one, many;
  tbb::task_arena(1).execute([&] { one = search(t, options, Progress::null()); });
  tbb::task_arena(4).execute([&] { many = search(t, options, Progress::null()); });
  EXPECT_EQ(one, many);
  // And the seed matters.
  EXPECT_NE(search(t, SearchOptions{4, 6, 9}, Progress::null()), one);
}

Bicluster make(std::vector<std::uint32_t> rows, std::vector<std::uint32_t> cols,
               std::vector<std::int32_t> constants) {
  return Bicluster{std::move(rows), std::move(cols), std::move(constants)};
}

TEST(BiclusterGroups, MergeJoinsOnlyIdenticalColumnsWithDisjointRows) {
  Biclustering b;
  b.rows = 20;
  b.cols = 10;
  b.biclusters = {
      make({0, 1}, {2, 5}, {3, 1}),  // kept
      make({7, 9}, {2, 5}, {3, 1}),  // joins the first: rows 0 1 7 9
      make({1, 4}, {2, 5}, {3, 1}),  // overlaps row 1: kept apart
      make({3}, {2, 5}, {3, 2}),     // other constant: kept apart
      make({5, 6}, {2, 6}, {3, 1}),  // other column: kept apart
      make({2, 8}, {2, 5}, {3, 1}),  // joins the first (sorted union)
      make({0, 9}, {2, 5}, {3, 2}),  // joins the fourth
  };
  b.residual = {{3, 3, 2}};
  const SparseCounts before = b.reconstruct();
  const std::int64_t cost = b.cost();
  EXPECT_EQ(merge_identical(b), 3u);
  EXPECT_EQ(b.reconstruct(), before);
  EXPECT_EQ(b.cost(), cost - 3 * (2 * 2 - 1));
  ASSERT_EQ(b.biclusters.size(), 4u);
  EXPECT_EQ(b.biclusters[0].rows, (std::vector<std::uint32_t>{0, 1, 2, 7, 8, 9}));
  EXPECT_EQ(b.biclusters[1].rows, (std::vector<std::uint32_t>{1, 4}));
  EXPECT_EQ(b.biclusters[2].rows, (std::vector<std::uint32_t>{0, 3, 9}));
  EXPECT_EQ(b.biclusters[3].cols, (std::vector<std::uint32_t>{2, 6}));
}

TEST(BiclusterGroups, MoreGroupsCostLittleOnCoherentInput) {
  // Columns constant over all vertices of a block: a group boundary cuts those biclusters and
  // the merge joins the pieces again, so the cost must not grow with the group count.
  SparseCounts t;
  t.rows = 64;
  t.cols = 12;
  for (std::size_t j = 0; j < t.rows; ++j) {
    for (std::uint32_t k = 0; k < t.cols; ++k) {
      if ((j + k) % 3 == 0) continue;
      t.columns.push_back(k);
      t.values.push_back(1 + static_cast<std::int32_t>(k % 4));
    }
    t.offsets.push_back(static_cast<std::uint32_t>(t.values.size()));
  }
  const std::int64_t one = search(t, SearchOptions{1, 1, 4}, Progress::null()).cost();
  for (int groups : {2, 4, 8}) {
    const Biclustering b = search(t, SearchOptions{1, groups, 4}, Progress::null());
    EXPECT_EQ(b.reconstruct(), t);
    EXPECT_LE(b.cost(), one + one / 4) << groups << " groups";
  }
}

}  // namespace
}  // namespace prt::bicluster
