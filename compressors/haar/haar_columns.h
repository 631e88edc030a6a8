#pragma once
// Ng 2003's relight order: T~ by light coefficient (column), so that a relight with a sparse
// light touches only the columns of its kept terms, sum over kept j of L~_j x T~[:, j]: the
// cost falls with the light's term count, where the row product (relight_haar) reads every
// row's k terms whatever the light holds.
//
// The columns are a layout derived from HaarArrays at construction (device bytes, never
// stored: the archive is the row layout). Rows are cut into blocks, each with its own column
// offsets, so that TBB runs the blocks in parallel (and the OpenCL column kernel one work-group
// per block, haar.cl) without two threads ever adding into the same row; within a block a column
// holds each row at most once. Values are decoded to float (s8: the code; the row's scale is
// applied to the row's sum).
#include <cstdint>
#include <span>
#include <vector>

#include "haar/haar.h"
#include "haar/haar_light.h"

namespace prt::haar {

class HaarColumns {
 public:
  static constexpr std::size_t kBlockRows = 4096;

  /// `block_rows` in 1..65536 (a row within its block is a u16).
  explicit HaarColumns(const HaarArrays& arrays, std::size_t block_rows = kBlockRows);

  /// out = T~ L~ for the kept terms of a wavelet-basis light (rows x RGB; every row written).
  /// Within float rounding of relight_haar with the dense light: the sums run in another order.
  void relight(const SparseLight& light, std::span<Rgb> out) const;
  /// Stored terms the relight of `light` reads (the sum of its columns' lengths).
  std::uint64_t touched_terms(const SparseLight& light) const;
  /// Bytes of the column layout (offsets, rows, values).
  std::uint64_t bytes() const;

  std::size_t block_rows() const { return block_rows_; }
  std::size_t blocks() const { return blocks_; }
  /// blocks x (N + 1): block b's column j is [offsets[b (N + 1) + j], offsets[b (N + 1) + j + 1]).
  std::span<const std::uint32_t> offsets() const { return offsets_; }
  std::span<const std::uint16_t> rows_in_block() const { return rows_in_block_; }
  std::span<const float> values() const { return values_; }
  std::span<const float> row_scales() const { return row_scales_; }  ///< empty unless s8

 private:
  std::size_t rows_ = 0, cols_ = 0;
  std::size_t block_rows_ = kBlockRows, blocks_ = 0;
  std::vector<std::uint32_t> offsets_;  ///< blocks x (cols + 1), absolute into rows_in_block_
  std::vector<std::uint16_t> rows_in_block_;
  std::vector<float> values_;      ///< decoded; s8: the code, the row scale applied at the end
  std::vector<float> row_scales_;  ///< s8 only
};

}  // namespace prt::haar
