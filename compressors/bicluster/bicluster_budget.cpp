#include "bicluster/bicluster_budget.h"

#include <algorithm>
#include <cstdlib>
#include <numeric>

#include "prtlab/base/error.h"

namespace prt::bicluster {

std::vector<std::int64_t> column_mass(const SparseCounts& t) {
  std::vector<std::int64_t> mass(t.cols, 0);
  for (std::size_t i = 0; i < t.nnz(); ++i) mass[t.columns[i]] += std::abs(t.values[i]);
  return mass;
}

BudgetResult drop_within_budget(Biclustering& b, std::span<const std::int64_t> column_mass,
                                double error) {
  PRT_CHECK(error >= 0.0 && error <= 1.0, "error {} outside [0, 1]", error);
  PRT_CHECK(column_mass.size() == b.cols, "{} column masses for {} columns", column_mass.size(),
            b.cols);
  BudgetResult result;
  consolidate_residual(b);
  if (error == 0.0) return result;  // every item has a positive mass: nothing can go

  // Items: biclusters 0 .. nb - 1, then residual terms.
  const std::size_t nb = b.biclusters.size();
  const std::size_t items = nb + b.residual.size();
  std::vector<std::int64_t> mass(items), flops(items);
  for (std::size_t i = 0; i < nb; ++i) {
    const Bicluster& bc = b.biclusters[i];
    std::int64_t sum = 0;
    for (std::int32_t t : bc.constants) sum += std::abs(t);
    mass[i] = static_cast<std::int64_t>(bc.rows.size()) * sum;
    flops[i] = bc.cost();
  }
  for (std::size_t i = 0; i < b.residual.size(); ++i) {
    mass[nb + i] = std::abs(b.residual[i].value);
    flops[nb + i] = 2;
  }
  std::vector<std::size_t> order(items);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) {
    // mass_x / flops_x < mass_y / flops_y, exactly (products of two int64 below 2^62 here).
    const long double lx = static_cast<long double>(mass[x]) * static_cast<long double>(flops[y]);
    const long double ly = static_cast<long double>(mass[y]) * static_cast<long double>(flops[x]);
    if (lx != ly) return lx < ly;
    if (mass[x] != mass[y]) return mass[x] < mass[y];
    return x < y;  // biclusters (lower indices) before residual terms
  });

  // Prefix mass per column over the order, dropped or not: the item's level is reached once
  // every column it touches holds the prefix within E times the column's mass.
  std::vector<std::int64_t> prefix(b.cols, 0), dropped_mass(b.cols, 0);
  std::vector<std::uint8_t> drop(items, 0);
  for (std::size_t i : order) {
    bool fits = true;
    auto visit = [&](std::uint32_t k, std::int64_t m) {
      prefix[k] += m;
      if (static_cast<double>(prefix[k]) > error * static_cast<double>(column_mass[k]))
        fits = false;
    };
    if (i < nb) {
      const Bicluster& bc = b.biclusters[i];
      const auto r = static_cast<std::int64_t>(bc.rows.size());
      for (std::size_t m = 0; m < bc.cols.size(); ++m)
        visit(bc.cols[m], r * std::abs(bc.constants[m]));
    } else {
      const Term& t = b.residual[i - nb];
      visit(t.col, std::abs(t.value));
    }
    if (!fits) continue;
    drop[i] = 1;
    result.flops_saved += flops[i];
    if (i < nb) {
      const Bicluster& bc = b.biclusters[i];
      const auto r = static_cast<std::int64_t>(bc.rows.size());
      for (std::size_t m = 0; m < bc.cols.size(); ++m)
        dropped_mass[bc.cols[m]] += r * std::abs(bc.constants[m]);
    } else {
      const Term& t = b.residual[i - nb];
      dropped_mass[t.col] += std::abs(t.value);
    }
  }
  for (std::size_t k = 0; k < b.cols; ++k) {
    if (dropped_mass[k] == 0) continue;
    PRT_CHECK(column_mass[k] > 0, "mass dropped from the empty column {}", k);
    result.bound = std::max(
        result.bound, static_cast<double>(dropped_mass[k]) / static_cast<double>(column_mass[k]));
  }

  std::vector<Bicluster> kept;
  kept.reserve(nb);
  for (std::size_t i = 0; i < nb; ++i) {
    if (drop[i]) {
      ++result.dropped_biclusters;
    } else {
      kept.push_back(std::move(b.biclusters[i]));
    }
  }
  b.biclusters = std::move(kept);
  std::vector<Term> terms;
  for (std::size_t i = 0; i < b.residual.size(); ++i) {
    if (drop[nb + i]) {
      ++result.dropped_terms;
    } else {
      terms.push_back(b.residual[i]);
    }
  }
  b.residual = std::move(terms);
  return result;
}

}  // namespace prt::bicluster
