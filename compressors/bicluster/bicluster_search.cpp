#include "bicluster/bicluster_search.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <iterator>
#include <map>
#include <optional>
#include <random>
#include <unordered_map>

#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/distributed/byte_stream.h"
#include "prtlab/distributed/shared_work.h"

namespace prt::bicluster {

std::int64_t Biclustering::cost() const {
  std::int64_t c = 0;
  for (const Bicluster& b : biclusters) c += b.cost();
  return c + 2 * static_cast<std::int64_t>(residual.size());
}

SparseCounts Biclustering::reconstruct() const {
  std::vector<std::map<std::uint32_t, std::int32_t>> dense(rows);
  for (const Bicluster& b : biclusters)
    for (std::uint32_t j : b.rows)
      for (std::size_t m = 0; m < b.cols.size(); ++m) dense[j][b.cols[m]] += b.constants[m];
  for (const Term& t : residual) dense[t.row][t.col] += t.value;
  SparseCounts out;
  out.rows = rows;
  out.cols = cols;
  for (const auto& row : dense) {
    for (const auto& [k, v] : row) {
      if (v == 0) continue;
      out.columns.push_back(k);
      out.values.push_back(v);
    }
    out.offsets.push_back(static_cast<std::uint32_t>(out.values.size()));
  }
  return out;
}

// ---- WorkingMatrix ----

WorkingMatrix::WorkingMatrix(const SparseCounts& m, std::size_t row_begin, std::size_t row_end)
    : rows_(row_end - row_begin), cols_(m.cols) {
  PRT_CHECK(row_begin <= row_end && row_end <= m.rows, "row range [{}, {}) of {} rows", row_begin,
            row_end, m.rows);
  // Sized first so that each column is allocated once.
  std::vector<std::uint32_t> col_size(m.cols, 0);
  for (std::uint32_t i = m.offsets[row_begin]; i < m.offsets[row_end]; ++i) {
    PRT_CHECK(m.columns[i] < m.cols, "column {} out of range", m.columns[i]);
    if (m.values[i] != 0) ++col_size[m.columns[i]];
  }
  for (std::size_t k = 0; k < m.cols; ++k) cols_[k].reserve(col_size[k]);
  for (std::size_t j = row_begin; j < row_end; ++j) {
    auto& row = rows_[j - row_begin];
    row.reserve(m.offsets[j + 1] - m.offsets[j]);
    const auto local = static_cast<std::uint32_t>(j - row_begin);
    for (std::uint32_t i = m.offsets[j]; i < m.offsets[j + 1]; ++i) {
      if (m.values[i] == 0) continue;
      row.push_back({m.columns[i], m.values[i]});
      cols_[m.columns[i]].push_back({local, m.values[i]});
      ++nnz_;
    }
  }
}

std::int32_t WorkingMatrix::get(std::uint32_t j, std::uint32_t k) const {
  const auto& r = rows_[j];
  const auto it = std::lower_bound(r.begin(), r.end(), k,
                                   [](const Entry& e, std::uint32_t c) { return e.col < c; });
  return it != r.end() && it->col == k ? it->value : 0;
}

int WorkingMatrix::row_add(std::uint32_t j, std::uint32_t k, std::int32_t delta) {
  auto& r = rows_[j];
  auto it = std::lower_bound(r.begin(), r.end(), k,
                             [](const Entry& e, std::uint32_t c) { return e.col < c; });
  if (it != r.end() && it->col == k) {
    it->value += delta;
    if (it->value != 0) return 0;
    r.erase(it);
    return -1;
  }
  r.insert(it, {k, delta});
  return 1;
}

void WorkingMatrix::add(std::uint32_t j, std::uint32_t k, std::int32_t delta) {
  if (delta == 0) return;
  const int change = row_add(j, k, delta);
  auto& c = cols_[k];
  auto it = std::lower_bound(c.begin(), c.end(), j,
                             [](const ColEntry& e, std::uint32_t row) { return e.row < row; });
  if (change > 0) {
    c.insert(it, {j, delta});
    ++nnz_;
  } else if (change < 0) {
    c.erase(it);
    --nnz_;
  } else {
    it->value += delta;
  }
}

void WorkingMatrix::subtract(const Bicluster& b) {
  for (std::uint32_t j : b.rows) {
    for (std::size_t m = 0; m < b.cols.size(); ++m) {
      const int change = row_add(j, b.cols[m], -b.constants[m]);
      if (change > 0) ++nnz_;
      if (change < 0) --nnz_;
    }
  }
  // Columns: a merge of the column's sorted rows with B's sorted rows.
  for (std::size_t m = 0; m < b.cols.size(); ++m) {
    auto& c = cols_[b.cols[m]];
    const std::int32_t t = b.constants[m];
    scratch_.clear();
    scratch_.reserve(c.size() + b.rows.size());
    std::size_t i = 0;
    for (std::uint32_t j : b.rows) {
      for (; i < c.size() && c[i].row < j; ++i) scratch_.push_back(c[i]);
      if (i < c.size() && c[i].row == j) {
        if (c[i].value != t) scratch_.push_back({j, c[i].value - t});
        ++i;
      } else {
        scratch_.push_back({j, -t});
      }
    }
    scratch_.insert(scratch_.end(), c.begin() + static_cast<std::ptrdiff_t>(i), c.end());
    c.swap(scratch_);
  }
}

// ---- GrowState ----

GrowState::GrowState(const WorkingMatrix& m)
    : m_(m),
      in_r_(m.rows(), 0),
      row_touched_(m.rows(), 0),
      match_(m.rows(), 0),
      nzc_(m.rows(), 0),
      row_version_(m.rows(), 0),
      in_c_(m.cols(), 0),
      col_touched_(m.cols(), 0),
      constant_(m.cols(), 0),
      nz_(m.cols(), 0),
      hist_(m.cols()),
      col_version_(m.cols(), 0) {}

void GrowState::reset() {
  for (std::uint32_t j : touched_rows_) {
    in_r_[j] = row_touched_[j] = 0;
    match_[j] = nzc_[j] = 0;
  }
  for (std::uint32_t k : touched_cols_) {
    in_c_[k] = col_touched_[k] = 0;
    constant_[k] = nz_[k] = 0;
    hist_[k].clear();
  }
  touched_rows_.clear();
  touched_cols_.clear();
  rows_in_.clear();
  cols_in_.clear();
  row_insert_ = Heap();
  row_delete_ = Heap();
  col_insert_ = Heap();
  col_delete_ = Heap();
  r_ = l_ = 0;
  gain_ = 1;  // the empty bicluster: W = -1, so dW = 1; a 1x1 on a non-zero then has dW = 0
}

void GrowState::start(std::uint32_t j, std::uint32_t k) {
  PRT_CHECK(m_.get(j, k) != 0, "seed ({}, {}) is zero", j, k);
  reset();
  insert_row(j);
  insert_col(k);
}

void GrowState::touch_row(std::uint32_t j) {
  if (row_touched_[j]) return;
  row_touched_[j] = 1;
  touched_rows_.push_back(j);
}
void GrowState::touch_col(std::uint32_t k) {
  if (col_touched_[k]) return;
  col_touched_[k] = 1;
  touched_cols_.push_back(k);
}

std::int32_t GrowState::hist_count(std::uint32_t k, std::int32_t v) const {
  for (const auto& [value, count] : hist_[k])
    if (value == v) return count;
  return 0;
}

void GrowState::hist_add(std::uint32_t k, std::int32_t v, int delta) {
  auto& h = hist_[k];
  for (auto it = h.begin(); it != h.end(); ++it) {
    if (it->first != v) continue;
    it->second += delta;
    if (it->second == 0) h.erase(it);
    return;
  }
  PRT_CHECK(delta > 0, "histogram of column {} lacks value {}", k, v);
  h.emplace_back(v, delta);
}

std::int32_t GrowState::candidate_constant(std::uint32_t k) const {
  std::int32_t best = 0, best_count = 0;
  for (const auto& [value, count] : hist_[k]) {
    // Most frequent; ties to the smaller value, so the choice does not depend on insertion order.
    if (count > best_count || (count == best_count && value < best)) {
      best = value;
      best_count = count;
    }
  }
  return best;
}

// Element cases of VI-A: equal to the constant +2, zero -2, another value 0. A row outside R
// gains -1 (r grows) plus its elements in C; a column outside C gains -2 (l grows) plus its
// elements in R. Deleting negates.
std::int64_t GrowState::row_influence(std::uint32_t j) const {
  const std::int64_t elements = 2 * match_[j] - 2 * (l_ - nzc_[j]);
  return in_r_[j] ? 1 - elements : -1 + elements;
}

std::int64_t GrowState::col_influence(std::uint32_t k) const {
  const std::int32_t t = in_c_[k] ? constant_[k] : candidate_constant(k);
  const std::int64_t elements = 2 * (t != 0 ? hist_count(k, t) : 0) - 2 * (r_ - nz_[k]);
  return in_c_[k] ? 2 - elements : -2 + elements;
}

// The bicluster keeps l >= 1 and r >= 1 while it grows, so an insertion whose key is at most 2
// can never have a positive influence (actual = key - 2l or key - 2r) until its key changes,
// which refreshes it again: such entries are not pushed (most touched rows and columns hold a
// single non-zero of the bicluster and would only fill the queues).
void GrowState::refresh_row(std::uint32_t j) {
  const std::uint32_t v = ++row_version_[j];
  const std::int64_t base = 2 * match_[j] + 2 * nzc_[j];
  if (in_r_[j]) {
    row_delete_.push({1 - base, j, v});  // + 2l
  } else if (-1 + base > 2) {
    row_insert_.push({-1 + base, j, v});  // - 2l
  }
}

void GrowState::refresh_col(std::uint32_t k) {
  const std::uint32_t v = ++col_version_[k];
  if (in_c_[k]) {
    col_delete_.push({2 - 2 * hist_count(k, constant_[k]) - 2 * nz_[k], k, v});  // + 2r
    return;
  }
  // hist <= nz, so the key -2 + 2 hist + 2 nz is at most 2 when nz <= 1: skip the histogram.
  if (nz_[k] <= 1) return;
  const std::int32_t t = candidate_constant(k);
  const std::int64_t key = -2 + 2 * (t != 0 ? hist_count(k, t) : 0) + 2 * nz_[k];
  if (key > 2) col_insert_.push({key, k, v});  // - 2r
}

void GrowState::insert_row(std::uint32_t j) {
  PRT_CHECK(!in_r_[j], "row {} already in the bicluster", j);
  gain_ += row_influence(j);
  touch_row(j);
  in_r_[j] = 1;
  rows_in_.push_back(j);
  ++r_;
  for (const auto& e : m_.row(j)) {
    touch_col(e.col);
    hist_add(e.col, e.value, 1);
    ++nz_[e.col];
    refresh_col(e.col);
  }
  refresh_row(j);
}

void GrowState::delete_row(std::uint32_t j) {
  PRT_CHECK(in_r_[j], "row {} is not in the bicluster", j);
  gain_ += row_influence(j);
  in_r_[j] = 0;
  rows_in_.erase(std::find(rows_in_.begin(), rows_in_.end(), j));
  --r_;
  for (const auto& e : m_.row(j)) {
    hist_add(e.col, e.value, -1);
    --nz_[e.col];
    refresh_col(e.col);
  }
  refresh_row(j);
}

void GrowState::insert_col(std::uint32_t k) {
  PRT_CHECK(!in_c_[k], "column {} already in the bicluster", k);
  const std::int32_t t = candidate_constant(k);
  PRT_CHECK(t != 0, "column {} has no non-zero in the bicluster's rows", k);
  gain_ += col_influence(k);
  touch_col(k);
  in_c_[k] = 1;
  constant_[k] = t;
  cols_in_.push_back(k);
  ++l_;
  for (const auto& e : m_.col(k)) {
    touch_row(e.row);
    ++nzc_[e.row];
    if (e.value == t) ++match_[e.row];
    refresh_row(e.row);
  }
  refresh_col(k);
}

void GrowState::delete_col(std::uint32_t k) {
  PRT_CHECK(in_c_[k], "column {} is not in the bicluster", k);
  gain_ += col_influence(k);
  const std::int32_t t = constant_[k];
  in_c_[k] = 0;
  constant_[k] = 0;
  cols_in_.erase(std::find(cols_in_.begin(), cols_in_.end(), k));
  --l_;
  for (const auto& e : m_.col(k)) {
    --nzc_[e.row];
    if (e.value == t) --match_[e.row];
    refresh_row(e.row);
  }
  refresh_col(k);
}

bool GrowState::top(Heap& heap, const std::vector<std::uint32_t>& version, bool member,
                    const std::vector<std::uint8_t>& in, Item& item) {
  while (!heap.empty()) {
    const Item& t = heap.top();
    if (t.version == version[t.id] && (in[t.id] != 0) == member) {
      item = t;
      return true;
    }
    heap.pop();
  }
  return false;
}

bool GrowState::best_op(Op& op) {
  bool found = false;
  auto consider = [&](OpKind kind, const Item& item, std::int64_t offset) {
    const std::int64_t influence = item.key + offset;
    if (influence > 0 && (!found || influence > op.influence)) {
      op = {kind, item.id, influence};
      found = true;
    }
  };
  Item item{};
  if (top(row_insert_, row_version_, false, in_r_, item))
    consider(OpKind::kInsertRow, item, -2 * l_);
  if (top(col_insert_, col_version_, false, in_c_, item))
    consider(OpKind::kInsertCol, item, -2 * r_);
  // The bicluster keeps at least one row and one column.
  if (r_ > 1 && top(row_delete_, row_version_, true, in_r_, item))
    consider(OpKind::kDeleteRow, item, 2 * l_);
  if (l_ > 1 && top(col_delete_, col_version_, true, in_c_, item))
    consider(OpKind::kDeleteCol, item, 2 * r_);
  return found;
}

void GrowState::apply(const Op& op) {
  switch (op.kind) {
    case OpKind::kInsertRow:
      insert_row(op.id);
      break;
    case OpKind::kDeleteRow:
      delete_row(op.id);
      break;
    case OpKind::kInsertCol:
      insert_col(op.id);
      break;
    case OpKind::kDeleteCol:
      delete_col(op.id);
      break;
  }
}

void GrowState::grow() {
  Op op{};
  while (best_op(op)) {
    const std::int64_t before = gain_;
    apply(op);
    PRT_CHECK(gain_ == before + op.influence, "queue influence {} disagrees with dW change {}",
              op.influence, gain_ - before);
  }
}

Bicluster GrowState::bicluster() const {
  Bicluster b;
  b.rows = rows_in_;
  b.cols = cols_in_;
  std::sort(b.rows.begin(), b.rows.end());
  std::sort(b.cols.begin(), b.cols.end());
  for (std::uint32_t k : b.cols) b.constants.push_back(constant_[k]);
  return b;
}

// ---- Algorithm 1 ----

Biclustering search_rows(const SparseCounts& t, std::size_t row_begin, std::size_t row_end,
                         std::uint64_t seed, Progress& progress) {
  WorkingMatrix work(t, row_begin, row_end);
  GrowState state(work);
  Biclustering out;
  out.rows = t.rows;
  out.cols = t.cols;
  const auto base = static_cast<std::uint32_t>(row_begin);
  // std::mt19937_64 is specified bit for bit; the distributions are not, so indices are drawn
  // by modulo (the bias is far below anything measurable at these sizes).
  std::mt19937_64 rng(seed);
  std::vector<std::uint32_t> order(work.rows());
  for (std::size_t j = 0; j < order.size(); ++j) order[j] = static_cast<std::uint32_t>(j);
  for (std::size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[rng() % i]);
  // A zero row never enters a bicluster (its insertion influence is -1 - 2l), so once a row is
  // cleared it stays clear: visiting rows in a random order and seeding at a random non-zero of
  // the current row until it is empty picks random non-zeros of T_c until T_c = 0.
  for (std::uint32_t j : order) {
    while (!work.row(j).empty()) {
      const auto row = work.row(j);
      const auto seed_entry = row[rng() % row.size()];
      const std::uint64_t nnz_before = work.nnz();
      state.start(j, seed_entry.col);
      state.grow();
      if (state.gain() > 0) {
        Bicluster b = state.bicluster();
        work.subtract(b);
        for (std::uint32_t& bj : b.rows) bj += base;
        out.biclusters.push_back(std::move(b));
      } else {
        out.residual.push_back({j + base, seed_entry.col, seed_entry.value});
        work.add(j, seed_entry.col, -seed_entry.value);
      }
      PRT_CHECK(work.nnz() < nnz_before, "a search step did not reduce nnz ({})", nnz_before);
    }
    progress.advance(1);
  }
  return out;
}

Biclustering search(const SparseCounts& t, std::uint64_t seed, Progress& progress) {
  Biclustering out = search_rows(t, 0, t.rows, seed, progress);
  progress.finish();
  return out;
}

std::vector<std::size_t> group_bounds(const SparseCounts& t, std::size_t rows_per_vertex,
                                      int groups) {
  PRT_CHECK(groups >= 1 && rows_per_vertex >= 1, "groups {} rows per vertex {}", groups,
            rows_per_vertex);
  PRT_CHECK(t.rows % rows_per_vertex == 0, "{} rows are not whole vertices of {} rows", t.rows,
            rows_per_vertex);
  const std::size_t vertices = t.rows / rows_per_vertex;
  const std::uint64_t nnz = t.offsets.back();
  std::vector<std::size_t> bounds{0};
  std::size_t v = 0;
  for (int g = 1; g < groups; ++g) {
    // The first vertex boundary at or past g/groups of the non-zeros.
    const std::uint64_t target =
        nnz * static_cast<std::uint64_t>(g) / static_cast<std::uint64_t>(groups);
    while (v < vertices && t.offsets[v * rows_per_vertex] < target) ++v;
    bounds.push_back(v * rows_per_vertex);
  }
  bounds.push_back(t.rows);
  return bounds;
}

std::uint64_t group_seed(std::uint64_t seed, int group) {
  if (group == 0) return seed;
  // SplitMix64 (Steele et al.) of the seed advanced by the group index.
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * static_cast<std::uint64_t>(group);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

namespace {

void put(ByteWriter& w, const Biclustering& b) {
  w.put<std::uint64_t>(b.biclusters.size());
  for (const Bicluster& c : b.biclusters) {
    w.put_array(c.rows);
    w.put_array(c.cols);
    w.put_array(c.constants);
  }
  w.put_array(b.residual);
}

Biclustering get(ByteReader& r) {
  Biclustering b;
  b.biclusters.resize(r.get<std::uint64_t>());
  for (Bicluster& c : b.biclusters) {
    c.rows = r.get_array<std::uint32_t>();
    c.cols = r.get_array<std::uint32_t>();
    c.constants = r.get_array<std::int32_t>();
  }
  b.residual = r.get_array<Term>();
  return b;
}

// The groups over the ranks of a collective run (prtlab compress under mpirun): a work queue
// hands them out, each rank searches its groups as one process would, and every rank receives
// every group's part, so the concatenation and merge below are those of one process.
std::vector<Biclustering> search_groups_on_ranks(Communicator& comm, const SparseCounts& t,
                                                 const std::vector<std::size_t>& bounds,
                                                 const SearchOptions& options, Progress& progress) {
  const std::size_t groups = bounds.size() - 1;
  log_debug("bicluster: {} groups over {} ranks", groups, comm.size());
  // Each thread of each rank takes groups from one queue until none is left.
  const std::vector<std::uint8_t> all =
      compute_on_all_ranks(comm, groups, [&](std::size_t g, std::vector<std::uint8_t>& out) {
        const Biclustering part = search_rows(
            t, bounds[g], bounds[g + 1], group_seed(options.seed, static_cast<int>(g)), progress);
        ByteWriter w(out);
        w.put<std::uint64_t>(g);
        put(w, part);
      });
  std::vector<Biclustering> parts(groups);
  std::vector<bool> seen(groups, false);
  ByteReader r(all, "bicluster groups");
  while (!r.done()) {
    const auto g = r.get<std::uint64_t>();
    PRT_CHECK(g < groups && !seen[g], "bicluster: group {} came twice or out of range", g);
    seen[g] = true;
    parts[g] = get(r);
  }
  for (std::size_t g = 0; g < groups; ++g)
    PRT_CHECK(seen[g], "bicluster: group {} of {} never arrived", g, groups);
  return parts;
}

}  // namespace

Biclustering search(const SparseCounts& t, const SearchOptions& options, Progress& progress) {
  PRT_CHECK(options.groups >= 1, "groups = {}", options.groups);
  const auto bounds = group_bounds(t, options.rows_per_vertex, options.groups);
  std::vector<Biclustering> parts(static_cast<std::size_t>(options.groups));
  if (Communicator* comm = collective(); comm && comm->distributed()) {
    parts = search_groups_on_ranks(*comm, t, bounds, options, progress);
  } else {
    // One task per group; each group's search is sequential with its own seed, so the parts do
    // not depend on which thread runs them.
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, parts.size(), 1),
        [&](const auto& range) {
          for (std::size_t g = range.begin(); g < range.end(); ++g) {
            const auto start = std::chrono::steady_clock::now();
            parts[g] = search_rows(t, bounds[g], bounds[g + 1],
                                   group_seed(options.seed, static_cast<int>(g)), progress);
            log_debug(
                "bicluster group {}: rows [{}, {}), {} biclusters, {:.2f} s on thread {}", g,
                bounds[g], bounds[g + 1], parts[g].biclusters.size(),
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
                tbb::this_task_arena::current_thread_index());
          }
        },
        tbb::simple_partitioner());
  }
  Biclustering out;
  out.rows = t.rows;
  out.cols = t.cols;
  for (auto& p : parts) {
    std::move(p.biclusters.begin(), p.biclusters.end(), std::back_inserter(out.biclusters));
    out.residual.insert(out.residual.end(), p.residual.begin(), p.residual.end());
    p = Biclustering();
  }
  merge_identical(out);
  progress.finish();
  return out;
}

namespace {
bool disjoint_sorted(const std::vector<std::uint32_t>& a, const std::vector<std::uint32_t>& b) {
  if (a.empty() || b.empty() || a.back() < b.front() || b.back() < a.front()) return true;
  std::size_t i = 0, k = 0;
  while (i < a.size() && k < b.size()) {
    if (a[i] == b[k]) return false;
    if (a[i] < b[k]) {
      ++i;
    } else {
      ++k;
    }
  }
  return true;
}

std::uint64_t columns_hash(const Bicluster& b) {
  std::uint64_t h = 0xcbf29ce484222325ull;  // FNV-1a over (column, constant) pairs
  for (std::size_t m = 0; m < b.cols.size(); ++m) {
    h = (h ^ b.cols[m]) * 0x100000001b3ull;
    h = (h ^ static_cast<std::uint32_t>(b.constants[m])) * 0x100000001b3ull;
  }
  return h;
}
}  // namespace

std::size_t merge_identical(Biclustering& b) {
  // Kept biclusters by the hash of (columns, constants); a key can hold several when their rows
  // overlap (possible within a group) or on a hash collision.
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> kept;
  kept.reserve(b.biclusters.size());
  std::vector<Bicluster> out;
  out.reserve(b.biclusters.size());
  std::size_t joins = 0;
  for (Bicluster& bc : b.biclusters) {
    auto& slots = kept[columns_hash(bc)];
    bool joined = false;
    for (std::size_t i : slots) {
      Bicluster& into = out[i];
      if (into.cols != bc.cols || into.constants != bc.constants ||
          !disjoint_sorted(into.rows, bc.rows))
        continue;
      const std::size_t mid = into.rows.size();
      into.rows.insert(into.rows.end(), bc.rows.begin(), bc.rows.end());
      if (into.rows[mid - 1] > into.rows[mid])
        std::inplace_merge(into.rows.begin(), into.rows.begin() + static_cast<std::ptrdiff_t>(mid),
                           into.rows.end());
      joined = true;
      ++joins;
      break;
    }
    if (joined) continue;
    slots.push_back(out.size());
    out.push_back(std::move(bc));
  }
  b.biclusters = std::move(out);
  return joins;
}

void consolidate_residual(Biclustering& b) {
  std::vector<Term>& terms = b.residual;
  std::sort(terms.begin(), terms.end(), [](const Term& x, const Term& y) {
    return x.row != y.row ? x.row < y.row : x.col < y.col;
  });
  std::size_t w = 0;
  for (std::size_t i = 0; i < terms.size();) {
    Term sum = terms[i];
    std::size_t e = i + 1;
    for (; e < terms.size() && terms[e].row == sum.row && terms[e].col == sum.col; ++e)
      sum.value += terms[e].value;
    if (sum.value != 0) terms[w++] = sum;
    i = e;
  }
  terms.resize(w);
}

}  // namespace prt::bicluster
