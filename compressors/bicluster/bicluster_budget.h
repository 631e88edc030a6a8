#pragma once
// The lossy mode of backend `bicluster` (beyond the paper, its future work): after the lossless
// search, drop whole items (biclusters and residual 1x1 terms) under a per-column L1 budget.
//
// Item i removes r_i |t_ik| of L1 mass from each of its columns k (a residual term: |v| from
// one). Column k may lose at most E * sum_j T[j, k] (T's column L1 mass, in counts). Because
// T >= 0, for every non-negative light L, per colour channel,
//     ||(T - T~) L||_1 <= sum_k L_k sum_{i dropped} r_i |t_ik| <= E sum_k L_k ||T_:k||_1
//                      = E ||T L||_1,
// the last step exact because T and L are non-negative. The guarantee is in relative L1.
//
// Order: increasing L1 mass per FLOP saved (mass_i / W_i; ties: smaller mass, then biclusters
// before residual terms, then index). Rule: item i is dropped iff in each of its columns the
// mass of i and of every item before it in the order (dropped or not) fits the budget. Each item
// thus has a level e_i = max_k prefix_k(i) / mass_k and the drop set at E is {i : e_i <= E}:
// nested in E, so the cost is non-increasing in E by construction. (Skipping an item that does
// not fit and going on, the plain greedy, is not monotone in E with items spanning several
// columns: a larger budget can admit an early item that then blocks two later ones.) E = 0
// drops nothing, every item having a positive mass.
#include <cstdint>
#include <span>
#include <vector>

#include "bicluster/bicluster_search.h"

namespace prt::bicluster {

/// sum_j |T[j, k]| per column k, in counts.
std::vector<std::int64_t> column_mass(const SparseCounts& t);

struct BudgetResult {
  std::size_t dropped_biclusters = 0;
  std::size_t dropped_terms = 0;
  std::int64_t flops_saved = 0;
  /// max_k (dropped mass in column k) / (column mass k): the relative L1 bound actually used,
  /// <= E (0 when nothing was dropped).
  double bound = 0.0;
};

/// Removes from `b` the items whose level is at most `error` (E in [0, 1]). The residual is
/// consolidated first (consolidate_residual), so a term is a whole position.
BudgetResult drop_within_budget(Biclustering& b, std::span<const std::int64_t> column_mass,
                                double error);

}  // namespace prt::bicluster
