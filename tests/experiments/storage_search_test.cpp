// The equal-storage search (experiments/storage_search.h) on storage curves known in closed
// form: continuous, logarithmic, stepped, integer, and out of reach.
#include "storage_search.h"

#include <gtest/gtest.h>

#include <cmath>

namespace prt::experiments {
namespace {

SizeKnob knob(double lo, double hi,
              SizeKnob::Direction d = SizeKnob::Direction::kLargerIsMoreStorage,
              SizeKnob::Scale s = SizeKnob::Scale::kLinear) {
  SizeKnob k{.key = std::string("k"), .direction = d, .min = lo, .max = hi, .scale = s};
  return k;
}

TEST(StorageSearch, LandsWithinToleranceOnALinearCurve) {
  // bytes = 1000 + 5e5 v: the target 2.0e5 is at v = 0.398.
  int calls = 0;
  const auto s = search_equal_storage(knob(0, 1), false, 200000, 0.05, 14, [&](double v) {
    ++calls;
    return static_cast<std::uint64_t>(1000 + 5e5 * v);
  });
  EXPECT_TRUE(s.reached) << s.note;
  EXPECT_LE(std::abs(s.ratio - 1.0), 0.05);
  EXPECT_EQ(static_cast<int>(s.probes.size()), calls);
  EXPECT_EQ(s.bytes, static_cast<std::uint64_t>(1000 + 5e5 * s.value));
}

TEST(StorageSearch, LandsOnADecreasingLogCurveWithATightTolerance) {
  // An error budget: bytes = 1e7 / (1 + 100 e), e in [1e-4, 1] on a log scale.
  const auto s = search_equal_storage(
      knob(1e-4, 1, SizeKnob::Direction::kLargerIsLessStorage, SizeKnob::Scale::kLog), false,
      1500000, 0.005, 30, [](double e) { return static_cast<std::uint64_t>(1e7 / (1 + 100 * e)); });
  EXPECT_TRUE(s.reached) << s.note;
  EXPECT_LE(std::abs(s.ratio - 1.0), 0.005);
  EXPECT_NEAR(s.value, (1e7 / 1.5e6 - 1) / 100, 0.01 * (1e7 / 1.5e6 - 1) / 100);
}

TEST(StorageSearch, IntegerKnobStopsWhenTheStepIsTooCoarse) {
  // 100 kB per cluster: 250 kB lies between 2 and 3 clusters, neither within 5 %.
  const auto s = search_equal_storage(knob(1, 64), true, 250000, 0.05, 20,
                                      [](double v) { return static_cast<std::uint64_t>(v * 1e5); });
  EXPECT_FALSE(s.reached);
  EXPECT_NE(s.note.find("jumps over"), std::string::npos) << s.note;
  EXPECT_TRUE(s.value == 2 || s.value == 3);
  for (const auto& p : s.probes) EXPECT_EQ(p.value, std::round(p.value));
  EXPECT_LT(s.probes.size(), 20u);
}

TEST(StorageSearch, IntegerKnobFindsAnExactValue) {
  const auto s = search_equal_storage(knob(1, 1000), true, 4170000, 0.01, 30,
                                      [](double v) { return static_cast<std::uint64_t>(v * 1e4); });
  EXPECT_TRUE(s.reached) << s.note;
  EXPECT_NEAR(s.value, 417, 4);
}

TEST(StorageSearch, SaysWhenTheTargetIsOutOfReach) {
  const auto f = [](double v) { return static_cast<std::uint64_t>(1e6 + 1e6 * v); };
  const auto below = search_equal_storage(knob(0, 1), false, 100000, 0.05, 10, f);
  EXPECT_FALSE(below.reached);
  EXPECT_NE(below.note.find("below the least storage"), std::string::npos) << below.note;
  EXPECT_EQ(below.value, 0);  // the closest end
  const auto above = search_equal_storage(knob(0, 1), false, 9000000, 0.05, 10, f);
  EXPECT_FALSE(above.reached);
  EXPECT_NE(above.note.find("above the most storage"), std::string::npos) << above.note;
  EXPECT_EQ(above.value, 1);
}

TEST(StorageSearch, PlateausAndStepsStillTerminate) {
  // A staircase with wide flat steps; the target sits on a step.
  const auto stairs = [](double v) {
    return static_cast<std::uint64_t>(1e5 * (1 + std::floor(v * 10)));
  };
  const auto s = search_equal_storage(knob(0, 1), false, 600000, 0.02, 40, stairs);
  EXPECT_TRUE(s.reached) << s.note;
  EXPECT_EQ(s.bytes, 600000u);
}

TEST(StorageSearch, ReachedWithinTheProbeBudgetOrSaysSo) {
  const auto s = search_equal_storage(knob(0, 1), false, 123456, 1e-9, 5, [](double v) {
    return static_cast<std::uint64_t>(1 + 1e6 * v * v);
  });
  EXPECT_LE(s.probes.size(), 5u);
  if (!s.reached) {
    EXPECT_NE(s.note.find("after 5 compressions"), std::string::npos) << s.note;
  }
}

TEST(StorageSearch, IntegerLogKnobTerminatesOnEveryUnreachableTarget) {
  // exp(log(n)) is not always n: the bracket must stay on exact integers.
  const auto k = knob(1, 1000, SizeKnob::Direction::kLargerIsMoreStorage, SizeKnob::Scale::kLog);
  for (std::uint64_t target = 150000; target < 3000000; target += 9973) {
    int calls = 0;
    const auto s = search_equal_storage(k, true, target, 0.01, 40, [&](double v) {
      ++calls;
      EXPECT_EQ(v, std::round(v));
      EXPECT_LE(calls, 40) << "target " << target;
      return static_cast<std::uint64_t>(v * 1e5);
    });
    EXPECT_LE(calls, 40);
    if (!s.reached) {
      EXPECT_NE(s.note.find("jumps over"), std::string::npos) << target << ": " << s.note;
    }
  }
}

TEST(StorageSearch, ARealKnobOnAStepCurveStopsAtTheStep) {
  // The target lies in the gap of a staircase: no value reaches it, and even 200 probes must
  // end with the jump named, not exhaust the budget.
  const auto stairs = [](double v) {
    return static_cast<std::uint64_t>(1e5 * (1 + std::floor(v * 10)));
  };
  const auto s = search_equal_storage(knob(0, 1), false, 550000, 0.02, 200, stairs);
  EXPECT_FALSE(s.reached);
  EXPECT_NE(s.note.find("jumps over"), std::string::npos) << s.note;
  EXPECT_LT(s.probes.size(), 200u);
  EXPECT_TRUE(s.bytes == 500000 || s.bytes == 600000);
}

TEST(StorageSearch, SaysWhenTheEndsContradictTheDeclaredDirection) {
  const auto s =
      search_equal_storage(knob(1, 19, SizeKnob::Direction::kLargerIsLessStorage), true, 500000,
                           0.05, 10, [](double v) { return static_cast<std::uint64_t>(1e5 * v); });
  EXPECT_FALSE(s.reached);
  EXPECT_NE(s.note.find("does not move the way"), std::string::npos) << s.note;
}

TEST(StorageSearch, PrefersAProbeWithinTheTolerance) {
  // Probes land at 1.051 and 0.9502 of the target: only the second is within 5 %.
  const auto s = search_equal_storage(knob(0, 1), false, 1000000, 0.05, 3, [](double v) {
    return static_cast<std::uint64_t>(v == 0 ? 10000 : v == 1 ? 1051000 : 950200);
  });
  EXPECT_TRUE(s.reached) << s.note;
  EXPECT_EQ(s.bytes, 950200u);
  EXPECT_TRUE(s.note.empty());
}

TEST(KnobValues, SpreadsOverTheScaleAndDeduplicatesIntegers) {
  const auto lin = knob_values(knob(0, 1), false, 5);
  ASSERT_EQ(lin.size(), 5u);
  EXPECT_DOUBLE_EQ(lin[2], 0.5);
  const auto lg = knob_values(
      knob(1e-3, 1, SizeKnob::Direction::kLargerIsLessStorage, SizeKnob::Scale::kLog), false, 4);
  ASSERT_EQ(lg.size(), 4u);
  EXPECT_NEAR(lg[1], 1e-2, 1e-12);
  EXPECT_DOUBLE_EQ(lg.front(), 1e-3);
  EXPECT_DOUBLE_EQ(lg.back(), 1.0);
  const auto ints = knob_values(knob(1, 3), true, 7);
  EXPECT_EQ(ints, (std::vector<double>{1, 2, 3}));
}

}  // namespace
}  // namespace prt::experiments
