// Ng 2003's relight order over the columns of T~ (haar_columns.h).
#include "haar/haar_columns.h"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "prtlab/base/error.h"
#include "prtlab/numeric/float16.h"

namespace prt::haar {
namespace {
typedef float Float4 __attribute__((vector_size(16)));
}  // namespace

HaarColumns::HaarColumns(const HaarArrays& a, std::size_t block_rows)
    : rows_(a.rows()), cols_(static_cast<std::size_t>(a.pixel_count)), block_rows_(block_rows) {
  PRT_CHECK(block_rows >= 1 && block_rows <= 65536, "haar columns: {} rows a block", block_rows);
  blocks_ = (rows_ + block_rows_ - 1) / block_rows_;
  offsets_.assign(blocks_ * (cols_ + 1), 0);
  rows_in_block_.resize(a.terms());
  values_.resize(a.terms());
  if (a.format == ValueFormat::kS8) row_scales_ = a.row_scales;
  const auto index = [&](std::size_t i) -> std::uint32_t {
    return a.wide ? a.indices32[i] : a.indices16[i];
  };
  const auto value = [&](std::size_t i) -> float {
    switch (a.format) {
      case ValueFormat::kFloat32:
        return a.values32[i];
      case ValueFormat::kFloat16:
        return half_to_float(a.values16[i]);
      case ValueFormat::kS8:
        return static_cast<float>(a.codes[i]);
    }
    return 0.f;
  };
  // Counting sort per block: column lengths, prefix sums, then the terms in row order, so each
  // column lists its rows rising.
  tbb::parallel_for(std::size_t{0}, blocks_, [&](std::size_t b) {
    const std::size_t first = b * block_rows_, last = std::min(rows_, first + block_rows_);
    std::uint32_t* off = &offsets_[b * (cols_ + 1)];
    for (std::uint32_t i = a.offsets[first]; i < a.offsets[last]; ++i) ++off[index(i) + 1];
    off[0] = a.offsets[first];
    for (std::size_t j = 0; j < cols_; ++j) off[j + 1] += off[j];
    std::vector<std::uint32_t> fill(off, off + cols_);
    for (std::size_t row = first; row < last; ++row)
      for (std::uint32_t i = a.offsets[row]; i < a.offsets[row + 1]; ++i) {
        const std::uint32_t at = fill[index(i)]++;
        rows_in_block_[at] = static_cast<std::uint16_t>(row - first);
        values_[at] = value(i);
      }
  });
}

void HaarColumns::relight(const SparseLight& light, std::span<Rgb> out) const {
  PRT_CHECK(out.size() == rows_ && light.indices.size() == light.values.size(),
            "haar column relight: output {} for {} rows, light {} / {}", out.size(), rows_,
            light.indices.size(), light.values.size());
  for (std::uint32_t j : light.indices)
    PRT_CHECK(j < cols_, "haar column relight: light index {} of N = {}", j, cols_);
  std::vector<Float4> l4(light.values.size());
  for (std::size_t t = 0; t < l4.size(); ++t)
    l4[t] = Float4{light.values[t].x, light.values[t].y, light.values[t].z, 0.f};
  tbb::parallel_for(std::size_t{0}, blocks_, [&](std::size_t b) {
    const std::size_t first = b * block_rows_, last = std::min(rows_, first + block_rows_);
    std::vector<Float4> acc(last - first, Float4{0.f, 0.f, 0.f, 0.f});
    const std::uint32_t* off = &offsets_[b * (cols_ + 1)];
    for (std::size_t t = 0; t < light.indices.size(); ++t) {
      const std::uint32_t j = light.indices[t];
      const Float4 l = l4[t];
      for (std::uint32_t e = off[j]; e < off[j + 1]; ++e) acc[rows_in_block_[e]] += values_[e] * l;
    }
    for (std::size_t row = first; row < last; ++row) {
      Float4 s = acc[row - first];
      if (!row_scales_.empty()) s *= row_scales_[row];
      out[row] = Rgb(s[0], s[1], s[2]);
    }
  });
}

std::uint64_t HaarColumns::touched_terms(const SparseLight& light) const {
  std::uint64_t n = 0;
  for (std::size_t b = 0; b < blocks_; ++b) {
    const std::uint32_t* off = &offsets_[b * (cols_ + 1)];
    for (std::uint32_t j : light.indices) n += off[j + 1] - off[j];
  }
  return n;
}

std::uint64_t HaarColumns::bytes() const {
  return offsets_.size() * sizeof(std::uint32_t) + rows_in_block_.size() * sizeof(std::uint16_t) +
         values_.size() * sizeof(float) + row_scales_.size() * sizeof(float);
}

}  // namespace prt::haar
