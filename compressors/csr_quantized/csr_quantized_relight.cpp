// The C++ relight of backend `csr_quantized`: the reference of csr_quantized.cl, which sums in
// the same order (four accumulators per row, combined as (a0 + a1) + (a2 + a3)).
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "csr_quantized/csr_quantized.h"
#include "csr_quantized/half_decode.h"
#include "prtlab/base/error.h"

namespace prt::csr_quantized {
namespace {

// RGB + pad in one 16-byte lane, as prt::relight_exact holds the light: one aligned load per
// gathered value, and the accumulators stay in SSE registers.
typedef float Float4 __attribute__((vector_size(16)));

// value(i): the float that multiplies the light at entry i (before the row scale).
template <typename Column, typename Value>
void product_rows(std::size_t begin, std::size_t end, const std::uint32_t* offsets,
                  const Column* columns, const Value& value, const float* row_scales,
                  const Float4* light, Rgb* out) {
  for (std::size_t row = begin; row < end; ++row) {
    Float4 a0{}, a1{}, a2{}, a3{};
    std::uint32_t i = offsets[row];
    const std::uint32_t e = offsets[row + 1];
    for (; i + 4 <= e; i += 4) {
      a0 += value(i + 0) * light[columns[i + 0]];
      a1 += value(i + 1) * light[columns[i + 1]];
      a2 += value(i + 2) * light[columns[i + 2]];
      a3 += value(i + 3) * light[columns[i + 3]];
    }
    for (; i < e; ++i) a0 += value(i) * light[columns[i]];
    Float4 sum = (a0 + a1) + (a2 + a3);
    if (row_scales != nullptr) sum *= row_scales[row];
    out[row] = Rgb(sum[0], sum[1], sum[2]);
  }
}

template <typename Column>
void relight_block(const QuantizedCsr& q, const Column* columns, const Float4* light,
                   std::span<Rgb> out, std::size_t begin, std::size_t end) {
  const std::uint32_t* offsets = q.offsets.data();
  switch (q.format) {
    case ValueFormat::kFloat32: {
      const float* v = q.values32.data();
      product_rows(
          begin, end, offsets, columns, [v](std::uint32_t i) { return v[i]; }, nullptr, light,
          out.data());
      break;
    }
    case ValueFormat::kFloat16: {
      const std::uint16_t* v = q.values16.data();
      product_rows(
          begin, end, offsets, columns, [v](std::uint32_t i) { return decode_finite_half(v[i]); },
          nullptr, light, out.data());
      break;
    }
    case ValueFormat::kU8: {
      const std::uint8_t* c = q.codes.data();
      product_rows(
          begin, end, offsets, columns, [c](std::uint32_t i) { return static_cast<float>(c[i]); },
          q.row_scales.data(), light, out.data());
      break;
    }
  }
}

}  // namespace

void relight_quantized(const QuantizedCsr& q, std::span<const Rgb> light, std::span<Rgb> out) {
  PRT_CHECK(light.size() == static_cast<std::size_t>(q.pixel_count) && out.size() == q.rows(),
            "csr_quantized relight: light {} / output {} values for {} rows x {} columns",
            light.size(), out.size(), q.rows(), q.pixel_count);
  std::vector<Float4> l4(light.size());
  for (std::size_t k = 0; k < light.size(); ++k)
    l4[k] = Float4{light[k].x, light[k].y, light[k].z, 0.f};
  // 1024 rows per task, as prt::relight_exact: enough work per task, fine enough to balance.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, q.rows(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      if (q.narrow_columns()) {
                        relight_block(q, q.columns16.data(), l4.data(), out, r.begin(), r.end());
                      } else {
                        relight_block(q, q.columns32.data(), l4.data(), out, r.begin(), r.end());
                      }
                    });
}

}  // namespace prt::csr_quantized
