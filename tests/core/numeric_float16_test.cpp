// IEEE binary16 conversion: every half value survives half -> float -> half, the float values
// are the ones the format defines, and float -> half rounds to nearest, ties to even, across
// every binade (including subnormals and the overflow threshold).
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include "prtlab/numeric/float16.h"

namespace prt {
namespace {

// The value the binary16 format assigns to these bits, computed independently in double.
double half_value(std::uint16_t h) {
  const int sign = h >> 15;
  const int e = (h >> 10) & 0x1f;
  const int m = h & 0x3ff;
  double v = 0.0;
  if (e == 0x1f) {
    v = m == 0 ? std::numeric_limits<double>::infinity() : std::numeric_limits<double>::quiet_NaN();
  } else if (e == 0) {
    v = std::ldexp(static_cast<double>(m), -24);
  } else {
    v = std::ldexp(static_cast<double>(1024 + m), e - 25);
  }
  return sign ? -v : v;
}

TEST(Float16, EveryHalfValueRoundTrips) {
  for (std::uint32_t bits = 0; bits < 0x10000u; ++bits) {
    const auto h = static_cast<std::uint16_t>(bits);
    const float f = half_to_float(h);
    const double expected = half_value(h);
    if (std::isnan(expected)) {
      EXPECT_TRUE(std::isnan(f)) << std::hex << bits;
      EXPECT_EQ(std::signbit(f), (bits & 0x8000u) != 0) << std::hex << bits;
      const std::uint16_t back = float_to_half(f);
      EXPECT_EQ(back & 0x7c00u, 0x7c00u) << std::hex << bits;
      EXPECT_NE(back & 0x3ffu, 0u) << std::hex << bits << " became infinity";
      continue;
    }
    EXPECT_EQ(static_cast<double>(f), expected) << std::hex << bits;
    EXPECT_EQ(std::signbit(f), (bits & 0x8000u) != 0) << std::hex << bits;
    EXPECT_EQ(float_to_half(f), h) << std::hex << bits;
  }
}

// Between two neighbouring halves a < b, the midpoint goes to the one with the even significand
// and anything strictly inside goes to the nearer one.
TEST(Float16, RoundsToNearestEvenBetweenEveryPairOfNeighbours) {
  for (std::uint32_t bits = 0; bits < 0x7bffu; ++bits) {
    for (const std::uint32_t sign : {0u, 0x8000u}) {
      const auto lo = static_cast<std::uint16_t>(bits | sign);
      const auto hi = static_cast<std::uint16_t>((bits + 1) | sign);
      const float a = half_to_float(lo);
      const float b = half_to_float(hi);
      // Exact: the midpoint of two halves needs 12 significant bits.
      const auto mid = static_cast<float>((static_cast<double>(a) + static_cast<double>(b)) / 2);
      const std::uint16_t even = (bits & 1u) == 0 ? lo : hi;
      EXPECT_EQ(float_to_half(mid), even) << std::hex << bits << " sign " << sign;
      EXPECT_EQ(float_to_half(std::nextafter(mid, a)), lo) << std::hex << bits;
      EXPECT_EQ(float_to_half(std::nextafter(mid, b)), hi) << std::hex << bits;
    }
  }
}

TEST(Float16, HandPickedValues) {
  EXPECT_EQ(float_to_half(0.0f), 0x0000);
  EXPECT_EQ(float_to_half(-0.0f), 0x8000);
  EXPECT_EQ(float_to_half(1.0f), 0x3c00);
  EXPECT_EQ(float_to_half(-2.0f), 0xc000);
  EXPECT_EQ(float_to_half(0.1f), 0x2e66);                   // 0.0999755859375
  EXPECT_EQ(float_to_half(1.0f / 3.0f), 0x3555);            // 0.333251953125
  EXPECT_EQ(float_to_half(1.0f + 0x1.0p-11f), 0x3c00);      // tie, down to even
  EXPECT_EQ(float_to_half(1.0f + 3 * 0x1.0p-11f), 0x3c02);  // tie, up to even
  EXPECT_EQ(float_to_half(65504.0f), 0x7bff);               // largest half
  EXPECT_EQ(float_to_half(65519.996f), 0x7bff);             // just below the tie
  EXPECT_EQ(float_to_half(65520.0f), 0x7c00);               // the tie goes to infinity
  EXPECT_EQ(float_to_half(1e10f), 0x7c00);
  EXPECT_EQ(float_to_half(-std::numeric_limits<float>::infinity()), 0xfc00);
  EXPECT_EQ(float_to_half(0x1.0p-14f), 0x0400);  // smallest normal
  EXPECT_EQ(float_to_half(0x1.0p-24f), 0x0001);  // smallest subnormal
  EXPECT_EQ(float_to_half(0x1.0p-25f), 0x0000);  // tie, down to even zero
  EXPECT_EQ(float_to_half(std::nextafter(0x1.0p-25f, 1.0f)), 0x0001);
  EXPECT_EQ(float_to_half(3 * 0x1.0p-25f), 0x0002);  // tie, up to even
  EXPECT_EQ(float_to_half(std::numeric_limits<float>::denorm_min()), 0x0000);
  EXPECT_EQ(float_to_half(std::nextafter(0x1.0p-14f, 0.0f)), 0x0400);  // rounds up to normal
  const std::uint16_t nan = float_to_half(std::numeric_limits<float>::quiet_NaN());
  EXPECT_EQ(nan & 0x7c00, 0x7c00);
  EXPECT_NE(nan & 0x3ff, 0);
  // A NaN whose payload lies only in the dropped bits must not turn into infinity.
  EXPECT_NE(float_to_half(std::bit_cast<float>(0x7f800001u)) & 0x3ff, 0);
}

}  // namespace
}  // namespace prt
