#include "bicluster/bicluster_search.h"

#include <algorithm>
#include <map>
#include <random>

#include "prtlab/error.h"

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

WorkingMatrix::WorkingMatrix(const SparseCounts& m) : rows_(m.rows), col_rows_(m.cols) {
  for (std::size_t j = 0; j < m.rows; ++j) {
    for (std::uint32_t i = m.offsets[j]; i < m.offsets[j + 1]; ++i) {
      if (m.values[i] == 0) continue;
      PRT_CHECK(m.columns[i] < m.cols, "column {} out of range", m.columns[i]);
      rows_[j].push_back({m.columns[i], m.values[i]});
      col_rows_[m.columns[i]].push_back(static_cast<std::uint32_t>(j));
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

void WorkingMatrix::add(std::uint32_t j, std::uint32_t k, std::int32_t delta) {
  if (delta == 0) return;
  auto& r = rows_[j];
  auto it = std::lower_bound(r.begin(), r.end(), k,
                             [](const Entry& e, std::uint32_t c) { return e.col < c; });
  auto& c = col_rows_[k];
  if (it != r.end() && it->col == k) {
    it->value += delta;
    if (it->value == 0) {
      r.erase(it);
      c.erase(std::lower_bound(c.begin(), c.end(), j));
      --nnz_;
    }
  } else {
    r.insert(it, {k, delta});
    c.insert(std::lower_bound(c.begin(), c.end(), j), j);
    ++nnz_;
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

void GrowState::refresh_row(std::uint32_t j) {
  const std::uint32_t v = ++row_version_[j];
  const std::int64_t base = 2 * match_[j] + 2 * nzc_[j];
  if (in_r_[j]) {
    row_delete_.push({1 - base, j, v});  // + 2l
  } else {
    row_insert_.push({-1 + base, j, v});  // - 2l
  }
}

void GrowState::refresh_col(std::uint32_t k) {
  const std::uint32_t v = ++col_version_[k];
  const std::int32_t t = in_c_[k] ? constant_[k] : candidate_constant(k);
  const std::int64_t base = 2 * (t != 0 ? hist_count(k, t) : 0) + 2 * nz_[k];
  if (in_c_[k]) {
    col_delete_.push({2 - base, k, v});  // + 2r
  } else {
    col_insert_.push({-2 + base, k, v});  // - 2r
  }
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
  for (std::uint32_t j : m_.col_rows(k)) {
    touch_row(j);
    ++nzc_[j];
    if (m_.get(j, k) == t) ++match_[j];
    refresh_row(j);
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
  for (std::uint32_t j : m_.col_rows(k)) {
    --nzc_[j];
    if (m_.get(j, k) == t) --match_[j];
    refresh_row(j);
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

Biclustering search(const SparseCounts& t, std::uint64_t seed, Progress& progress) {
  WorkingMatrix work(t);
  GrowState state(work);
  Biclustering out;
  out.rows = t.rows;
  out.cols = t.cols;
  // std::mt19937_64 is specified bit for bit; the distributions are not, so indices are drawn
  // by modulo (the bias is far below anything measurable at these sizes).
  std::mt19937_64 rng(seed);
  std::vector<std::uint32_t> order(t.rows);
  for (std::size_t j = 0; j < t.rows; ++j) order[j] = static_cast<std::uint32_t>(j);
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
        for (std::uint32_t bj : b.rows)
          for (std::size_t m = 0; m < b.cols.size(); ++m) work.add(bj, b.cols[m], -b.constants[m]);
        out.biclusters.push_back(std::move(b));
      } else {
        out.residual.push_back({j, seed_entry.col, seed_entry.value});
        work.add(j, seed_entry.col, -seed_entry.value);
      }
      PRT_CHECK(work.nnz() < nnz_before, "a search step did not reduce nnz ({})", nnz_before);
    }
    progress.advance(1);
  }
  progress.finish();
  return out;
}

}  // namespace prt::bicluster
