// Pareto fronts (experiments/pareto_front.h) on hand-made points, checked against a brute-force
// dominance test.
#include "pareto_front.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace prt::experiments {
namespace {

TEST(ParetoFront, HandMadePoints) {
  //            0          1          2          3          4           5
  std::vector<CostError> p = {{1, 10}, {2, 5}, {3, 6}, {4, 1}, {2, 5}, {0.5, NAN}};
  // 2 is dominated by 1; 4 duplicates 1 (the first is kept); 5 has a NaN.
  EXPECT_EQ(pareto_front(p), (std::vector<std::size_t>{0, 1, 3}));
}

TEST(ParetoFront, EqualCostKeepsTheLowerError) {
  std::vector<CostError> p = {{1, 3}, {1, 2}, {1, 2.5}};
  EXPECT_EQ(pareto_front(p), (std::vector<std::size_t>{1}));
}

TEST(ParetoFront, EqualErrorKeepsTheLowerCost) {
  std::vector<CostError> p = {{5, 1}, {2, 1}, {9, 0.5}};
  EXPECT_EQ(pareto_front(p), (std::vector<std::size_t>{1, 2}));
}

TEST(ParetoFront, AgreesWithBruteForceDominance) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> d(0, 20);  // coarse values: many ties
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<CostError> p(30);
    for (auto& q : p) q = {static_cast<double>(d(rng)), static_cast<double>(d(rng))};
    std::vector<std::size_t> expected;
    for (std::size_t i = 0; i < p.size(); ++i) {
      bool dominated = false;
      for (std::size_t j = 0; j < p.size() && !dominated; ++j) {
        const bool le = p[j].cost <= p[i].cost && p[j].error <= p[i].error;
        const bool lt = p[j].cost < p[i].cost || p[j].error < p[i].error;
        dominated = (le && lt) || (j < i && p[j].cost == p[i].cost && p[j].error == p[i].error);
      }
      if (!dominated) expected.push_back(i);
    }
    auto got = pareto_front(p);
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, expected) << "trial " << trial;
  }
}

}  // namespace
}  // namespace prt::experiments
