#pragma once
// The greedy bicluster search of Sun et al., "Biclustering for all-frequency bi-scale PRT"
// (sections IV-B, IV-C, VI-A, Algorithm 1), on the integer counts of T (so it is exact).
//
// A constant-column bicluster B[rows; cols; t_1..t_l] stands for the r x l submatrix whose
// column m is t_m everywhere; B L costs W(B) = r + 2l - 1 FLOPs. A search grows one bicluster
// from a random non-zero of the working matrix T_c by row/column insertions and deletions, always
// taking the operation of largest positive influence on
//     dW(M) = 2 nnz(M) - (r + 2l - 1) - 2 nnz(M_R),   M = T_c[rows; cols], M_R = M - B,
// read from four lazy priority queues whose keys are updated locally after each operation (the
// three element cases +2 / -2 / 0 of VI-A). A new column's constant is the most frequent
// non-zero value of the column in the current rows. When no operation has a positive influence
// the bicluster is accepted if dW > 0 (T_c -= B, residual entries stay in T_c, possibly
// negative) or else the seed element becomes a 1x1 residual term. Each step lowers nnz(T_c), so
// the loop ends with T_c = 0 and sum B_i + residual = T exactly.
#include <cstdint>
#include <queue>
#include <span>
#include <vector>

#include "prtlab/base/progress.h"

namespace prt::bicluster {

/// A sparse matrix of signed integer counts in CSR (columns strictly increasing per row).
struct SparseCounts {
  std::size_t rows = 0;
  std::size_t cols = 0;
  std::vector<std::uint32_t> offsets{0};
  std::vector<std::uint32_t> columns;
  std::vector<std::int32_t> values;
  std::size_t nnz() const { return values.size(); }
  friend bool operator==(const SparseCounts&, const SparseCounts&) = default;
};

struct Bicluster {
  std::vector<std::uint32_t> rows;      ///< strictly increasing
  std::vector<std::uint32_t> cols;      ///< strictly increasing
  std::vector<std::int32_t> constants;  ///< t_m per column, non-zero counts
  /// W(B) = r + 2l - 1.
  std::int64_t cost() const {
    return static_cast<std::int64_t>(rows.size()) + 2 * static_cast<std::int64_t>(cols.size()) - 1;
  }
  friend bool operator==(const Bicluster&, const Bicluster&) = default;
};

/// A residual 1x1 term (a seed whose bicluster did not pay off).
struct Term {
  std::uint32_t row = 0;
  std::uint32_t col = 0;
  std::int32_t value = 0;
  friend bool operator==(const Term&, const Term&) = default;
};

struct Biclustering {
  std::size_t rows = 0;
  std::size_t cols = 0;
  std::vector<Bicluster> biclusters;
  std::vector<Term> residual;
  /// FLOPs of one product: sum W(B_i) + 2 per residual term (a 1x1 bicluster: 1 + 2 - 1).
  std::int64_t cost() const;
  /// sum B_i + residual, as CSR counts (zeros dropped).
  SparseCounts reconstruct() const;
  friend bool operator==(const Biclustering&, const Biclustering&) = default;
};

/// The residual matrix T_c, editable: rows of (column, value) and columns of (row, value), both
/// sorted, so an entry is found by binary search and a column's rows and values are listed
/// directly. Built from a contiguous row range of a SparseCounts, renumbered from 0, so a group
/// of rows is searched with memory proportional to its size.
class WorkingMatrix {
 public:
  struct Entry {
    std::uint32_t col;
    std::int32_t value;
  };
  struct ColEntry {
    std::uint32_t row;
    std::int32_t value;
  };
  explicit WorkingMatrix(const SparseCounts& m) : WorkingMatrix(m, 0, m.rows) {}
  /// Rows [row_begin, row_end) of m as rows 0 .. row_end - row_begin - 1.
  WorkingMatrix(const SparseCounts& m, std::size_t row_begin, std::size_t row_end);

  std::size_t rows() const { return rows_.size(); }
  std::size_t cols() const { return cols_.size(); }
  std::uint64_t nnz() const { return nnz_; }
  std::span<const Entry> row(std::size_t j) const { return rows_[j]; }
  std::span<const ColEntry> col(std::size_t k) const { return cols_[k]; }
  std::int32_t get(std::uint32_t j, std::uint32_t k) const;
  /// T_c[j, k] += delta (keeps both indexes sorted and zeros out of them).
  void add(std::uint32_t j, std::uint32_t k, std::int32_t delta);
  /// T_c[rows, cols] -= B: one pass over each of B's rows and columns (B's rows and columns
  /// sorted), instead of a search and a shift of the column per element.
  void subtract(const Bicluster& b);

 private:
  // Row j's entry for column k += delta; returns +1 / -1 / 0 as an entry appears / vanishes.
  int row_add(std::uint32_t j, std::uint32_t k, std::int32_t delta);
  std::vector<std::vector<Entry>> rows_;
  std::vector<std::vector<ColEntry>> cols_;
  std::vector<ColEntry> scratch_;
  std::uint64_t nnz_ = 0;
};

/// The growth of one bicluster over a WorkingMatrix, with the incremental bookkeeping of VI-A.
/// Exposed so tests can compare it with a brute-force recount.
class GrowState {
 public:
  enum class OpKind { kInsertRow, kInsertCol, kDeleteRow, kDeleteCol };
  struct Op {
    OpKind kind;
    std::uint32_t id;
    std::int64_t influence;
  };

  explicit GrowState(const WorkingMatrix& m);
  /// Starts a 1x1 bicluster at the non-zero (j, k).
  void start(std::uint32_t j, std::uint32_t k);

  /// Influence of inserting (when outside) or deleting (when inside) row j / column k on dW.
  std::int64_t row_influence(std::uint32_t j) const;
  std::int64_t col_influence(std::uint32_t k) const;
  /// The constant a new column k would get (0 when the column has no non-zero in the rows).
  std::int32_t candidate_constant(std::uint32_t k) const;
  /// dW of the current bicluster, kept by summing the influences of applied operations.
  std::int64_t gain() const { return gain_; }
  bool has_row(std::uint32_t j) const { return in_r_[j] != 0; }
  bool has_col(std::uint32_t k) const { return in_c_[k] != 0; }
  std::int32_t constant(std::uint32_t k) const { return constant_[k]; }

  void insert_row(std::uint32_t j);
  void delete_row(std::uint32_t j);
  void insert_col(std::uint32_t k);
  void delete_col(std::uint32_t k);
  /// The operation of largest influence from the queues (ties: row insert, column insert, row
  /// delete, column delete, then smaller id); none when no influence is positive.
  bool best_op(Op& op);
  void apply(const Op& op);
  /// Applies best ops until none improves dW.
  void grow();
  Bicluster bicluster() const;

 private:
  struct Item {
    std::int64_t key;
    std::uint32_t id;
    std::uint32_t version;
    bool operator<(const Item& o) const { return key != o.key ? key < o.key : id > o.id; }
  };
  using Heap = std::priority_queue<Item>;
  void reset();
  void touch_row(std::uint32_t j);
  void touch_col(std::uint32_t k);
  void refresh_row(std::uint32_t j);
  void refresh_col(std::uint32_t k);
  std::int32_t hist_count(std::uint32_t k, std::int32_t v) const;
  void hist_add(std::uint32_t k, std::int32_t v, int delta);
  bool top(Heap& heap, const std::vector<std::uint32_t>& version, bool member,
           const std::vector<std::uint8_t>& in, Item& item);

  const WorkingMatrix& m_;
  std::int64_t r_ = 0, l_ = 0, gain_ = 0;
  // Per row: membership, #columns of C where the row equals the constant, #non-zeros in C.
  std::vector<std::uint8_t> in_r_, row_touched_;
  std::vector<std::int32_t> match_, nzc_;
  std::vector<std::uint32_t> row_version_, touched_rows_;
  // Per column: membership, constant, #non-zeros in the rows R, histogram of those values.
  std::vector<std::uint8_t> in_c_, col_touched_;
  std::vector<std::int32_t> constant_, nz_;
  std::vector<std::vector<std::pair<std::int32_t, std::int32_t>>> hist_;
  std::vector<std::uint32_t> col_version_, touched_cols_;
  std::vector<std::uint32_t> rows_in_, cols_in_;
  // Keys exclude the terms common to all rows (l) / columns (r): actual = key -/+ 2l or 2r.
  Heap row_insert_, row_delete_, col_insert_, col_delete_;
};

/// How the rows are split for a parallel search.
struct SearchOptions {
  std::uint64_t seed = 1;
  /// Number of row groups searched independently (>= 1). Groups are contiguous ranges of whole
  /// vertices (boundaries at multiples of rows_per_vertex) holding about nnz / groups non-zeros
  /// each; group g is searched with group_seed(seed, g). The result depends on (seed, groups)
  /// and T only, never on the thread count.
  int groups = 1;
  std::size_t rows_per_vertex = 1;  ///< M; 1 lets a group boundary fall between any rows
};

/// The groups' row boundaries: groups + 1 non-decreasing values from 0 to t.rows (a group may
/// be empty when one vertex holds more than its share).
std::vector<std::size_t> group_bounds(const SparseCounts& t, std::size_t rows_per_vertex,
                                      int groups);
/// Seed of group g: `seed` itself for group 0 (so groups = 1 is the single search), a SplitMix64
/// hash of (seed, g) for the others.
std::uint64_t group_seed(std::uint64_t seed, int group);

/// Algorithm 1 over `t` (deterministic for a seed). Progress counts visited rows (its total
/// should be t.rows, as the compression stage sets it). Equivalent to search with one group,
/// without the merge.
Biclustering search(const SparseCounts& t, std::uint64_t seed, Progress& progress);

/// Algorithm 1 over rows [row_begin, row_end) of `t` only; the result's rows are global.
Biclustering search_rows(const SparseCounts& t, std::size_t row_begin, std::size_t row_end,
                         std::uint64_t seed, Progress& progress);

/// The grouped search: the groups run in parallel (TBB), their results are concatenated in
/// group order and merge_identical() joins the pieces of biclusters cut by group boundaries.
Biclustering search(const SparseCounts& t, const SearchOptions& options, Progress& progress);

/// Joins biclusters with identical columns and constants and disjoint rows (rows unioned, at
/// the position of the first): each join saves 2l - 1 FLOPs and changes no product. Returns the
/// number of joins.
std::size_t merge_identical(Biclustering& b);

/// Sums residual terms at the same position and drops zeros (terms sorted by row, then column).
void consolidate_residual(Biclustering& b);

}  // namespace prt::bicluster
