// 8-bit block quantisation: every entry within its half-step bound, the step as small as the
// block's range allows, exact round trips for values on the grid, the non-negative range, and
// refusal of values it cannot represent; codes linear in x^(1 / gamma) meet the derived bound
// s (1 - (1 - 1/510)^gamma) and come within a few per cent of it (the bound is tight).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/numeric/quantization.h"

namespace prt {
namespace {

constexpr std::uint64_t kSeed = 20240613;

std::vector<double> random_values(std::size_t count, double lo, double hi, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(lo, hi);
  std::vector<double> v(count);
  for (double& x : v) x = u(rng);
  return v;
}

struct Case {
  QuantizationRange range;
  std::size_t block;
  double lo, hi;
};

class QuantizationCases : public ::testing::TestWithParam<Case> {};

TEST_P(QuantizationCases, EveryEntryIsWithinHalfAStepAndTheStepIsTight) {
  const Case c = GetParam();
  const std::size_t rows = 37, cols = 50;
  const std::vector<double> x = random_values(rows * cols, c.lo, c.hi, kSeed);
  const QuantizedBlocks q = quantize_u8(x, rows, cols, {c.range, c.block});
  ASSERT_EQ(q.codes.size(), rows * cols);
  ASSERT_EQ(q.scales.size(), rows * q.blocks_per_row());
  const std::vector<double> back = dequantize(q);
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t col = 0; col < cols; ++col) {
      const std::size_t e = r * cols + col;
      const double err = std::abs(x[e] - back[e]);
      EXPECT_LE(err, q.error_bound(r, col))
          << "entry (" << r << ", " << col << "), seed " << kSeed << ", error "
          << err / q.scales[q.block_of(r, col)] << " steps";
      EXPECT_EQ(back[e], q.dequantize(r, col));
    }
  }
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t b = 0; b < q.blocks_per_row(); ++b) {
      const std::size_t begin = r * cols + b * q.block_size;
      const std::size_t end = std::min(begin + q.block_size, (r + 1) * cols);
      const double lo = *std::min_element(x.begin() + begin, x.begin() + end);
      const double hi = *std::max_element(x.begin() + begin, x.begin() + end);
      const double offset = q.offsets[r * q.blocks_per_row() + b];
      const double scale = q.scales[r * q.blocks_per_row() + b];
      const double base = c.range == QuantizationRange::kNonNegative ? 0.0 : lo;
      if (c.range == QuantizationRange::kNonNegative) {
        EXPECT_EQ(offset, 0.0);
      }
      // The offset is the block minimum rounded down to a float, and the step the smallest
      // float step that still reaches the maximum: one float ulp of slack each, no more.
      EXPECT_LE(offset, base);
      EXPECT_GE(offset, base - std::abs(base) * 0x1.0p-23);
      EXPECT_GE(offset + 255.0 * scale, hi);
      EXPECT_LE(scale, (hi - offset) / 255.0 * (1.0 + 0x1.0p-22)) << "row " << r;
      // The bound is half a step; the rest is double rounding.
      const double top = std::max(std::abs(offset), std::abs(offset + 255.0 * scale));
      EXPECT_LE(q.error_bound(r, b * q.block_size) - 0.5 * scale, 1e-15 * top);
      // The extreme values use the extreme codes. A one-value block may use either, and the
      // minimum sits above code 0 when the float offset had to round down by half a step or more.
      if (c.range == QuantizationRange::kAffine && lo < hi && lo - offset < 0.5 * scale) {
        EXPECT_EQ(q.codes[std::min_element(x.begin() + begin, x.begin() + end) - x.begin()], 0);
      }
      EXPECT_EQ(q.codes[std::max_element(x.begin() + begin, x.begin() + end) - x.begin()], 255);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Numeric, QuantizationCases,
                         ::testing::Values(Case{QuantizationRange::kAffine, 0, -3.0, 5.0},
                                           Case{QuantizationRange::kAffine, 7, -3.0, 5.0},
                                           Case{QuantizationRange::kAffine, 16, 1000.0, 1000.5},
                                           Case{QuantizationRange::kAffine, 50, -1e-6, 1e-6},
                                           Case{QuantizationRange::kNonNegative, 0, 0.0, 1.0},
                                           Case{QuantizationRange::kNonNegative, 9, 0.0, 300.0}));

TEST(Quantization, ValuesOnTheGridRoundTripExactly) {
  std::mt19937_64 rng(kSeed);
  for (const QuantizationRange range :
       {QuantizationRange::kAffine, QuantizationRange::kNonNegative}) {
    const std::size_t rows = 20, cols = 40, block = 10;
    std::vector<double> x(rows * cols);
    std::vector<std::uint8_t> codes(rows * cols);
    std::vector<float> offsets, scales;
    for (std::size_t r = 0; r < rows; ++r) {
      for (std::size_t b = 0; b < cols / block; ++b) {
        const float offset = range == QuantizationRange::kAffine
                                 ? static_cast<float>(rng() % 2000) / 7.0f - 100.0f
                                 : 0.0f;
        const float scale = static_cast<float>(1 + rng() % 1000) / 3.0e3f;
        offsets.push_back(offset);
        scales.push_back(scale);
        for (std::size_t i = 0; i < block; ++i) {
          const std::size_t e = r * cols + b * block + i;
          // Codes 0 and 255 pin the block's range to the grid's.
          codes[e] = i == 0 ? 0 : i == 1 ? 255 : static_cast<std::uint8_t>(rng() % 256);
          x[e] = static_cast<double>(offset) + static_cast<double>(scale) * codes[e];
        }
      }
    }
    const QuantizedBlocks q = quantize_u8(x, rows, cols, {range, block});
    EXPECT_EQ(q.offsets, offsets) << "seed " << kSeed;
    EXPECT_EQ(q.scales, scales) << "seed " << kSeed;
    EXPECT_EQ(q.codes, codes) << "seed " << kSeed;
    EXPECT_EQ(dequantize(q), x) << "seed " << kSeed;
  }
}

TEST(Quantization, FloatInputEqualsTheSameValuesAsDouble) {
  const std::vector<double> d = random_values(12 * 30, -2.0, 2.0, kSeed);
  std::vector<float> f(d.size());
  std::vector<double> fd(d.size());
  for (std::size_t i = 0; i < d.size(); ++i) fd[i] = f[i] = static_cast<float>(d[i]);
  const QuantizedBlocks a = quantize_u8(f, 12, 30, {QuantizationRange::kAffine, 8});
  const QuantizedBlocks b = quantize_u8(fd, 12, 30, {QuantizationRange::kAffine, 8});
  EXPECT_EQ(a.codes, b.codes);
  EXPECT_EQ(a.scales, b.scales);
  EXPECT_EQ(a.offsets, b.offsets);
}

TEST(Quantization, ConstantBlocksAreExact) {
  const std::vector<double> x{0.25, 0.25, 0.25, -7.5, -7.5, -7.5};
  const QuantizedBlocks q = quantize_u8(x, 2, 3);
  EXPECT_EQ(q.scales, (std::vector<float>{0.0f, 0.0f}));
  EXPECT_EQ(dequantize(q), x);
  // 0.1 is not a float: the offset rounds below it, and one step reaches it.
  const std::vector<double> tenth{0.1, 0.1};
  const QuantizedBlocks t = quantize_u8(tenth, 1, 2);
  EXPECT_GT(t.scales[0], 0.0f);
  for (const double v : dequantize(t)) EXPECT_LE(std::abs(v - 0.1), t.error_bound(0, 0));
}

TEST(Quantization, RejectsWhatItCannotRepresent) {
  const std::vector<double> x{1.0, -0.5, 2.0, 3.0};
  EXPECT_THROW(quantize_u8(x, 2, 3), ParameterError);
  EXPECT_THROW(quantize_u8(x, 2, 2, {QuantizationRange::kNonNegative, 0}), ParameterError);
  const std::vector<double> nan{1.0, std::numeric_limits<double>::quiet_NaN()};
  EXPECT_THROW(quantize_u8(nan, 1, 2), ParameterError);
  const std::vector<double> huge{-1e300, 1e300};
  EXPECT_THROW(quantize_u8(huge, 1, 2), ParameterError);
}

// What render/factored_material.h does with code_gamma: y = x^(1 / gamma) quantised under
// kNonNegative, decoded y~^gamma in double and stored as float.
std::vector<double> gamma_round_trip(const std::vector<double>& x, double gamma) {
  std::vector<double> y(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) y[i] = std::pow(x[i], 1.0 / gamma);
  QuantizationOptions o;
  o.range = QuantizationRange::kNonNegative;
  const QuantizedBlocks q = quantize_u8(y, 1, y.size(), o);
  std::vector<double> back(x.size());
  for (std::size_t i = 0; i < x.size(); ++i)
    back[i] = static_cast<float>(std::pow(q.dequantize(0, i), gamma));
  return back;
}

TEST(QuantizationGammaCodes, MeetTheDerivedBoundAndAttainIt) {
  for (double gamma : {1.0, 2.2, 3.0}) {
    for (double s : {1.0, 7.5e-3}) {
      std::vector<double> x = random_values(20000, 0.0, s, kSeed + 1);
      x.push_back(s);  // the block's maximum is s
      const std::vector<double> back = gamma_round_trip(x, gamma);
      const double bound = gamma_code_error_bound(s, gamma);
      // The float scale and the float decoding: relative rounding of gamma 2^-24 of s each.
      const double rounding = 4 * gamma * 0x1.0p-24 * s;
      double worst = 0;
      for (std::size_t i = 0; i < x.size(); ++i) {
        const double err = std::abs(back[i] - x[i]);
        worst = std::max(worst, err);
        EXPECT_LE(err, bound + rounding) << "gamma " << gamma << " s " << s << " x " << x[i];
      }
      // Tight: 20,000 uniform values put about 20000 * 2h (1 - h)^(gamma - 1) / gamma of them
      // in the top code's rounding interval, so the largest error is within a few per cent.
      EXPECT_GT(worst, 0.95 * bound) << "gamma " << gamma << " s " << s;
      // Against linear codes at the same s, gamma > 1 trades top precision for bottom steps.
      EXPECT_NEAR(bound / (s / 510.0), gamma, 0.01 * gamma);
    }
  }
  // The closed form: gamma 2.2 at s = 1.
  EXPECT_NEAR(gamma_code_error_bound(1.0, 2.2), 1.0 - std::pow(1.0 - 1.0 / 510.0, 2.2), 1e-15);
  EXPECT_THROW(gamma_code_error_bound(1.0, 0.5), ParameterError);
  EXPECT_THROW(gamma_code_error_bound(-1.0, 2.2), ParameterError);
}

}  // namespace
}  // namespace prt
