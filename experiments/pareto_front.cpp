#include "pareto_front.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace prt::experiments {

std::vector<std::size_t> pareto_front(const std::vector<CostError>& points) {
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (!std::isnan(points[i].cost) && !std::isnan(points[i].error)) order.push_back(i);
  // By cost, then error, then index: a sweep keeps each point whose error is below every error
  // seen so far (strictly, so equal points after the first are dominated or duplicates).
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (points[a].cost != points[b].cost) return points[a].cost < points[b].cost;
    return points[a].error < points[b].error;
  });
  std::vector<std::size_t> front;
  double best = INFINITY;
  for (std::size_t i : order) {
    if (points[i].error < best) {
      front.push_back(i);
      best = points[i].error;
    }
  }
  return front;
}

}  // namespace prt::experiments
