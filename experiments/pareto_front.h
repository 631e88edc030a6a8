#pragma once
// Pareto fronts of (cost, error) points, both minimised: run time or storage against error.
#include <cstddef>
#include <vector>

namespace prt::experiments {

struct CostError {
  double cost = 0;
  double error = 0;
};

/// Indices of the points no other point dominates (another is <= in both coordinates and < in
/// one), sorted by increasing cost. Points with a NaN coordinate are never on the front and
/// never dominate; of exact duplicates the first is kept.
std::vector<std::size_t> pareto_front(const std::vector<CostError>& points);

}  // namespace prt::experiments
