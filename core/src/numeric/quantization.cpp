#include "prtlab/numeric/quantization.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "prtlab/base/error.h"

namespace prt {

namespace {

constexpr double kCodes = 255.0;
// Four units of rounding of the largest grid value: one for the double evaluation of
// offset + scale * code, one for the encoder's comparison of neighbours, and one for the
// containment test of the block's maximum, with one to spare.
constexpr double kRoundingUnits = 4.0 * 0x1.0p-53;

float float_below(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

double decode(float offset, float scale, int code) {
  return static_cast<double>(offset) + static_cast<double>(scale) * code;
}

// The smallest float scale whose top grid value, as decode() evaluates it, reaches hi.
float covering_scale(float offset, double hi) {
  if (hi <= static_cast<double>(offset)) return 0.0f;
  constexpr float kInf = std::numeric_limits<float>::infinity();
  float s = static_cast<float>((hi - static_cast<double>(offset)) / kCodes);
  while (std::isfinite(s) && decode(offset, s, 255) < hi) s = std::nextafter(s, kInf);
  while (s > 0.0f && decode(offset, std::nextafter(s, 0.0f), 255) >= hi) {
    s = std::nextafter(s, 0.0f);
  }
  return s;
}

std::uint8_t encode(double x, float offset, float scale) {
  if (scale == 0.0f) return 0;
  const double t = (x - static_cast<double>(offset)) / static_cast<double>(scale);
  const int c0 = static_cast<int>(std::clamp(std::floor(t), 0.0, 254.0));
  const double d0 = std::abs(x - decode(offset, scale, c0));
  const double d1 = std::abs(x - decode(offset, scale, c0 + 1));
  return static_cast<std::uint8_t>(d1 < d0 ? c0 + 1 : c0);
}

template <class T>
QuantizedBlocks quantize(std::span<const T> values, std::size_t rows, std::size_t cols,
                         const QuantizationOptions& o) {
  if (values.size() != rows * cols) {
    throw ParameterError(fmt::format("quantize_u8: {} values given for {} rows of {} columns",
                                     values.size(), rows, cols));
  }
  QuantizedBlocks q;
  q.rows = rows;
  q.cols = cols;
  q.range = o.range;
  q.block_size = o.block_size == 0 || o.block_size > cols ? cols : o.block_size;
  q.codes.resize(rows * cols);
  const std::size_t blocks = q.blocks_per_row();
  q.scales.resize(rows * blocks);
  q.offsets.resize(rows * blocks);
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t b = 0; b < blocks; ++b) {
      const std::size_t begin = r * cols + b * q.block_size;
      const std::size_t end = std::min(begin + q.block_size, (r + 1) * cols);
      double lo = std::numeric_limits<double>::infinity();
      double hi = -lo;
      for (std::size_t e = begin; e < end; ++e) {
        const auto x = static_cast<double>(values[e]);
        if (!std::isfinite(x)) {
          throw ParameterError(
              fmt::format("quantize_u8: entry ({}, {}) is {}", r, e - r * cols, x));
        }
        lo = std::min(lo, x);
        hi = std::max(hi, x);
      }
      float offset = 0.0f;
      if (o.range == QuantizationRange::kNonNegative) {
        if (lo < 0.0) {
          throw ParameterError(fmt::format(
              "quantize_u8: row {} has the negative value {} but the range is non-negative; use "
              "the affine range",
              r, lo));
        }
      } else {
        offset = float_below(lo);
      }
      const float scale = covering_scale(offset, hi);
      if (!std::isfinite(offset) || !std::isfinite(scale)) {
        throw ParameterError(fmt::format(
            "quantize_u8: row {} spans [{}, {}], which a float offset and scale cannot hold", r, lo,
            hi));
      }
      q.offsets[r * blocks + b] = offset;
      q.scales[r * blocks + b] = scale;
      for (std::size_t e = begin; e < end; ++e) {
        q.codes[e] = encode(static_cast<double>(values[e]), offset, scale);
      }
    }
  }
  return q;
}

}  // namespace

std::size_t QuantizedBlocks::blocks_per_row() const {
  return block_size == 0 ? 0 : (cols + block_size - 1) / block_size;
}

double QuantizedBlocks::dequantize(std::size_t row, std::size_t col) const {
  const std::size_t b = block_of(row, col);
  return decode(offsets[b], scales[b], codes[row * cols + col]);
}

double QuantizedBlocks::error_bound(std::size_t row, std::size_t col) const {
  const std::size_t b = block_of(row, col);
  const double top = std::max(std::abs(static_cast<double>(offsets[b])),
                              std::abs(decode(offsets[b], scales[b], 255)));
  return 0.5 * static_cast<double>(scales[b]) + kRoundingUnits * top;
}

QuantizedBlocks quantize_u8(std::span<const double> values, std::size_t rows, std::size_t cols,
                            const QuantizationOptions& options) {
  return quantize(values, rows, cols, options);
}

QuantizedBlocks quantize_u8(std::span<const float> values, std::size_t rows, std::size_t cols,
                            const QuantizationOptions& options) {
  return quantize(values, rows, cols, options);
}

std::vector<double> dequantize(const QuantizedBlocks& q) {
  std::vector<double> out(q.rows * q.cols);
  for (std::size_t r = 0; r < q.rows; ++r) {
    for (std::size_t c = 0; c < q.cols; ++c) out[r * q.cols + c] = q.dequantize(r, c);
  }
  return out;
}

double gamma_code_error_bound(double block_max, double gamma) {
  if (!(gamma >= 1.0) || !std::isfinite(gamma) || !(block_max >= 0.0) || !std::isfinite(block_max))
    throw ParameterError(fmt::format(
        "gamma code error bound: gamma {} must be finite and >= 1, block_max {} finite and >= 0",
        gamma, block_max));
  return block_max * -std::expm1(gamma * std::log1p(-1.0 / 510.0));
}

}  // namespace prt
