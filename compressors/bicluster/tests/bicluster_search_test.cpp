// Backend `bicluster`, beyond the conformance suite: the incremental bookkeeping of the greedy
// search (VI-A) against a brute-force recount, exact reconstruction of the counts, the cost
// bound of the all-1x1 representation, determinism per seed, and the FLOP / storage accounting.
#include "bicluster/bicluster_search.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <set>

#include "bicluster/bicluster.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/geometry/procedural_shapes.h"
#include "prtlab/transfer/random_transfer.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt::bicluster {
namespace {

using Dense = std::vector<std::vector<std::int32_t>>;

// A dense matrix with few distinct values (0 with probability `zero`, else 1..values).
Dense random_dense(std::mt19937_64& rng, std::size_t rows, std::size_t cols, double zero,
                   int values) {
  Dense d(rows, std::vector<std::int32_t>(cols, 0));
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (auto& row : d)
    for (auto& v : row)
      if (u(rng) >= zero) v = 1 + static_cast<std::int32_t>(rng() % static_cast<unsigned>(values));
  return d;
}

SparseCounts to_sparse(const Dense& d) {
  SparseCounts s;
  s.rows = d.size();
  s.cols = d.empty() ? 0 : d[0].size();
  for (const auto& row : d) {
    for (std::size_t k = 0; k < row.size(); ++k) {
      if (row[k] == 0) continue;
      s.columns.push_back(static_cast<std::uint32_t>(k));
      s.values.push_back(row[k]);
    }
    s.offsets.push_back(static_cast<std::uint32_t>(s.values.size()));
  }
  return s;
}

// Eq. (9) recounted from scratch for rows R, columns C with constants t.
std::int64_t brute_gain(const Dense& d, const std::set<std::uint32_t>& rows,
                        const std::map<std::uint32_t, std::int32_t>& cols) {
  std::int64_t nnz_m = 0, nnz_r = 0;
  for (std::uint32_t j : rows) {
    for (const auto& [k, t] : cols) {
      if (d[j][k] != 0) ++nnz_m;
      if (d[j][k] != t) ++nnz_r;
    }
  }
  const auto r = static_cast<std::int64_t>(rows.size());
  const auto l = static_cast<std::int64_t>(cols.size());
  return 2 * nnz_m - (r + 2 * l - 1) - 2 * nnz_r;
}

// The published constant of a new column: the most frequent non-zero in the rows (ties: the
// smaller value); 0 when there is none.
std::int32_t brute_constant(const Dense& d, const std::set<std::uint32_t>& rows, std::uint32_t k) {
  std::map<std::int32_t, int> count;
  for (std::uint32_t j : rows)
    if (d[j][k] != 0) ++count[d[j][k]];
  std::int32_t best = 0;
  int best_count = 0;
  for (const auto& [v, c] : count)
    if (c > best_count) best = v, best_count = c;
  return best;
}

TEST(BiclusterSearch, IncrementalInfluencesMatchABruteForceRecount) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 40; ++trial) {
    const std::size_t rows = 4 + rng() % 9, cols = 4 + rng() % 9;
    const Dense d = random_dense(rng, rows, cols, 0.45, 1 + static_cast<int>(rng() % 3));
    const SparseCounts s = to_sparse(d);
    if (s.nnz() == 0) continue;
    const WorkingMatrix work(s);
    GrowState state(work);
    // Seed at a random non-zero.
    std::uint32_t sj = 0, sk = 0;
    do {
      sj = static_cast<std::uint32_t>(rng() % rows);
      sk = static_cast<std::uint32_t>(rng() % cols);
    } while (d[sj][sk] == 0);
    state.start(sj, sk);
    std::set<std::uint32_t> rset{sj};
    std::map<std::uint32_t, std::int32_t> cset{{sk, d[sj][sk]}};
    for (int step = 0; step < 30; ++step) {
      const std::int64_t gain = brute_gain(d, rset, cset);
      ASSERT_EQ(state.gain(), gain) << "trial " << trial << " step " << step;
      std::int64_t best = 0;
      for (std::uint32_t j = 0; j < rows; ++j) {
        auto r2 = rset;
        if (r2.contains(j)) {
          r2.erase(j);
        } else {
          r2.insert(j);
        }
        const std::int64_t expect = brute_gain(d, r2, cset) - gain;
        ASSERT_EQ(state.row_influence(j), expect) << "row " << j << " trial " << trial;
        if (!r2.empty()) best = std::max(best, expect);
      }
      for (std::uint32_t k = 0; k < cols; ++k) {
        auto c2 = cset;
        if (c2.contains(k)) {
          c2.erase(k);
        } else {
          const std::int32_t t = brute_constant(d, rset, k);
          ASSERT_EQ(state.candidate_constant(k), t) << "column " << k;
          if (t == 0) continue;  // never inserted: no non-zero in the rows
          c2[k] = t;
        }
        const std::int64_t expect = brute_gain(d, rset, c2) - gain;
        ASSERT_EQ(state.col_influence(k), expect) << "column " << k << " trial " << trial;
        if (!c2.empty()) best = std::max(best, expect);
      }
      // The queue's front is the best positive operation.
      GrowState::Op op{};
      const bool found = state.best_op(op);
      ASSERT_EQ(found, best > 0);
      if (found) {
        ASSERT_EQ(op.influence, best);
      }
      // A random operation (also non-improving ones, to exercise every update).
      const bool on_row = rng() % 2 == 0;
      if (on_row) {
        const auto j = static_cast<std::uint32_t>(rng() % rows);
        if (rset.contains(j)) {
          if (rset.size() == 1) continue;
          state.delete_row(j);
          rset.erase(j);
        } else {
          state.insert_row(j);
          rset.insert(j);
        }
      } else {
        const auto k = static_cast<std::uint32_t>(rng() % cols);
        if (cset.contains(k)) {
          if (cset.size() == 1) continue;
          state.delete_col(k);
          cset.erase(k);
        } else {
          const std::int32_t t = brute_constant(d, rset, k);
          if (t == 0) continue;
          state.insert_col(k);
          cset[k] = t;
        }
      }
      ASSERT_EQ(state.bicluster().rows, std::vector<std::uint32_t>(rset.begin(), rset.end()));
    }
  }
}

TEST(BiclusterSearch, ReconstructsRandomSparseMatricesExactlyAndNeverCostsMoreThan1x1) {
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 30; ++trial) {
    const Dense d = random_dense(rng, 10 + rng() % 40, 10 + rng() % 40, 0.3 + 0.6 * (trial % 3) / 2,
                                 1 + static_cast<int>(rng() % 4));
    const SparseCounts s = to_sparse(d);
    const Biclustering b = search(s, trial, Progress::null());
    EXPECT_EQ(b.reconstruct(), s) << "trial " << trial;
    EXPECT_LE(b.cost(), 2 * static_cast<std::int64_t>(s.nnz())) << "trial " << trial;
    for (const Bicluster& bc : b.biclusters) {
      EXPECT_GT(bc.cost(), 0);
      EXPECT_TRUE(std::is_sorted(bc.rows.begin(), bc.rows.end()));
      EXPECT_EQ(bc.cols.size(), bc.constants.size());
    }
  }
}

TEST(BiclusterSearch, FindsThePlantedBlock) {
  // A 6 x 5 block of constant columns in an otherwise empty matrix costs 6 + 10 - 1 = 15 as one
  // bicluster, against 60 as 1x1 terms: the search must get well below the all-1x1 cost.
  Dense d(20, std::vector<std::int32_t>(20, 0));
  const std::vector<std::uint32_t> rows = {1, 4, 5, 9, 13, 17}, cols = {0, 3, 8, 11, 19};
  for (std::uint32_t j : rows)
    for (std::size_t m = 0; m < cols.size(); ++m)
      d[j][cols[m]] = static_cast<std::int32_t>(1 + m % 3);
  const Biclustering b = search(to_sparse(d), 3, Progress::null());
  EXPECT_EQ(b.reconstruct(), to_sparse(d));
  EXPECT_EQ(b.cost(), 15);
  ASSERT_EQ(b.biclusters.size(), 1u);
  EXPECT_EQ(b.biclusters[0].rows, rows);
  EXPECT_EQ(b.biclusters[0].cols, cols);
}

TEST(BiclusterSearch, SameSeedSameBiclusters) {
  std::mt19937_64 rng(5);
  const SparseCounts s = to_sparse(random_dense(rng, 60, 50, 0.5, 3));
  const Biclustering a = search(s, 42, Progress::null());
  const Biclustering b = search(s, 42, Progress::null());
  EXPECT_EQ(a, b);
  EXPECT_FALSE(a.biclusters.empty());
}

std::unique_ptr<CompressedTransfer> compress(const TransferMatrix& t, int resolution, int side) {
  const CubemapLayout cubemap(resolution);
  const HemisphereGrid grid(side);
  return CompressorRegistry::instance()
      .create("bicluster", {{"seed", "9"}})
      ->compress({t, nullptr, cubemap, grid}, Progress::null());
}

void expect_exact(const TransferMatrix& t, const CompressedTransfer& ct) {
  const auto& bt = dynamic_cast<const BiclusterTransfer&>(ct);
  EXPECT_EQ(reconstruct(bt.arrays()), counts_of(t));
  EXPECT_LE(ct.flops_per_relight(), 2.0 * static_cast<double>(t.nnz()));
  // FLOPs = sum W(B_i) (residual terms as 1x1 biclusters), recounted from the arrays.
  const BiclusterArrays& a = bt.arrays();
  const std::size_t nb = a.bicluster_count();
  std::vector<std::int64_t> rows_of(nb, 0);
  for (std::size_t s = 0; s < a.slice_count(); ++s)
    for (int lane = 0; lane < kSliceRows; ++lane)
      a.for_each_id(s, lane, [&](std::uint32_t i) { ++rows_of.at(i); });
  double flops = 0;
  for (std::size_t i = 0; i < nb; ++i) {
    if (i % kZeroStride == 0) {
      EXPECT_EQ(rows_of[i], 0) << "zero slot " << i << " has rows";
      EXPECT_EQ(a.bic_col_offsets[i + 1], a.bic_col_offsets[i]) << "zero slot " << i;
      continue;
    }
    EXPECT_GT(rows_of[i], 0) << "bicluster " << i << " has no row";
    flops +=
        static_cast<double>(rows_of[i] + 2 * (a.bic_col_offsets[i + 1] - a.bic_col_offsets[i]) - 1);
  }
  EXPECT_EQ(ct.flops_per_relight(), flops);
  // The padding and jumps are small: slices of rows sorted by length.
  EXPECT_LE(static_cast<double>(a.slice_codes.size() - a.incidences()),
            0.5 * static_cast<double>(a.slice_codes.size()) + 64);
  std::uint64_t bytes = 4;
  for (const auto& c : ct.storage().components)
    if (c.name != "scale") bytes += c.bytes;
  EXPECT_EQ(ct.storage().total_bytes(), bytes);
}

TEST(BiclusterBackend, RandomTransferIsReconstructedExactly) {
  const TransferMatrix t = random_transfer(17, RandomTransferSpec{30, 3, 3, 2, 0.4, {4}});
  const auto ct = compress(t, 3, 3);
  expect_exact(t, *ct);
}

TEST(BiclusterBackend, TinySceneIsReconstructedExactlyAndCompressed) {
  Mesh mesh = make_plane(3.0, 3.0, 3);
  Mesh sphere = make_sphere(0.5, 10, 5);
  for (auto& p : sphere.positions) p += Vec3(0.2f, 0.8f, -0.1f);
  mesh.append(sphere, 1);
  TransferParams params;
  params.cubemap_resolution = 6;
  params.local_grid = 3;
  params.supersampling = 2;
  params.show_progress = false;
  const TransferMatrix t = compute_transfer(mesh, params).transfer;
  ASSERT_GT(t.nnz(), 0u);
  const auto ct = compress(t, 6, 3);
  expect_exact(t, *ct);
  // Real visibility is coherent: the biclustering must beat the CSR product's 2 nnz clearly.
  EXPECT_LT(ct->flops_per_relight(), 0.9 * 2.0 * static_cast<double>(t.nnz()));
}

}  // namespace
}  // namespace prt::bicluster
