#pragma once
// 8-bit quantisation of rows of reals with one scale (and offset) per row or per block of a row,
// as Suykens 2003 stores normalised BTF factors in 8-bit textures. Scales and offsets are floats
// (what a GPU texture or buffer holds); a code c decodes to offset + scale * c evaluated in
// double. Encoding picks the code whose decoded value is nearest, so every entry is within half
// a step of its original.
//
// Gamma-coded blocks. A material stores non-negative values x of a block (largest s) as codes
// linear in y = x^(1 / gamma) (kNonNegative on y, decoded x~ = y~^gamma; gamma 1 is linear,
// render/factored_material.h's `code_gamma` defaults to 2.2 like an sRGB texture). With
// u = (x / s)^(1 / gamma) in [0, 1] and the decoded u~ = k / 255 within h = 1/510 of it (half a
// step), |x~ - x| = s |u~^gamma - u^gamma|. For gamma >= 1 the slope gamma u^(gamma - 1) grows
// with u, so over |u~ - u| <= h with both in [0, 1] the difference is largest against the top
// code: |x~ - x| <= s (1 - (1 - h)^gamma) (about s gamma / 510: 0.43 % of s at gamma 2.2, twice
// linear codes' 0.20 %, the price of steps s (1/255)^gamma ~ 5e-6 s at the bottom). It is
// attained by an x just above s (1 - h)^gamma, the midpoint between the top two codes, which
// rounds up to s. gamma_code_error_bound gives it; the float scale and float decoding add
// relative rounding of order gamma 2^-24 of s.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace prt {

enum class QuantizationRange {
  kAffine,       ///< per block: offset = min, scale = (max - min) / 255
  kNonNegative,  ///< per block: offset = 0, scale = max / 255; refuses negative values
};

struct QuantizationOptions {
  QuantizationRange range = QuantizationRange::kAffine;
  /// Entries per scale block within a row; 0 or >= cols: one block per row. The last block of
  /// a row may be shorter.
  std::size_t block_size = 0;
};

struct QuantizedBlocks {
  std::size_t rows = 0;
  std::size_t cols = 0;
  std::size_t block_size = 0;  ///< entries per block (the resolved value, never 0 unless cols is)
  QuantizationRange range = QuantizationRange::kAffine;
  std::vector<std::uint8_t> codes;  ///< rows x cols, row after row
  std::vector<float> scales;        ///< rows x blocks_per_row()
  std::vector<float> offsets;       ///< rows x blocks_per_row(); all 0 for kNonNegative

  std::size_t blocks_per_row() const;
  std::size_t block_of(std::size_t row, std::size_t col) const {
    return row * blocks_per_row() + col / block_size;
  }
  /// offset + scale * code of entry (row, col).
  double dequantize(std::size_t row, std::size_t col) const;
  /// The largest |x - dequantize(x)| any entry of that entry's block can have: half a step,
  /// plus the rounding of the double evaluation of offset + scale * code.
  double error_bound(std::size_t row, std::size_t col) const;
};

/// Quantises a rows x cols row-major array. Throws ParameterError on a size mismatch, a value
/// that is not finite, a block whose range does not fit a float scale, or a negative value under
/// kNonNegative.
QuantizedBlocks quantize_u8(std::span<const double> values, std::size_t rows, std::size_t cols,
                            const QuantizationOptions& options = {});
QuantizedBlocks quantize_u8(std::span<const float> values, std::size_t rows, std::size_t cols,
                            const QuantizationOptions& options = {});

/// All entries, row after row.
std::vector<double> dequantize(const QuantizedBlocks& q);

/// The worst-case |x~ - x| of 8-bit codes linear in x^(1 / gamma) over a block of values in
/// [0, block_max], gamma >= 1 (above): block_max (1 - (1 - 1/510)^gamma), without rounding.
double gamma_code_error_bound(double block_max, double gamma);

}  // namespace prt
