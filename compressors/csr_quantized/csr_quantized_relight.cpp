// The C++ relight of backend `csr_quantized`: the reference of csr_quantized.cl, which sums in
// the same order (four accumulators per row, combined as (a0 + a1) + (a2 + a3)). The full and the
// vertex-subset relight share RowSum, so a subset row has the full relight's bits.
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
struct RowSum {
  const std::uint32_t* offsets;
  const Column* columns;
  Value value;
  const float* row_scales;  // format u8 only, else null
  const Float4* light;

  Rgb operator()(std::size_t row) const {
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
    return Rgb(sum[0], sum[1], sum[2]);
  }
};

template <typename Column, typename Value>
RowSum<Column, Value> row_sum(const QuantizedCsr& q, const Column* columns, Value value,
                              const float* row_scales, const Float4* light) {
  return {q.offsets.data(), columns, value, row_scales, light};
}

// Calls fn(sum) with the RowSum of q's column width and value format.
template <typename Fn>
void with_row_sum(const QuantizedCsr& q, const Float4* light, const Fn& fn) {
  const auto by_columns = [&](const auto* columns) {
    switch (q.format) {
      case ValueFormat::kFloat32: {
        const float* v = q.values32.data();
        fn(row_sum(
            q, columns, [v](std::uint32_t i) { return v[i]; }, nullptr, light));
        break;
      }
      case ValueFormat::kFloat16: {
        const std::uint16_t* v = q.values16.data();
        fn(row_sum(
            q, columns, [v](std::uint32_t i) { return decode_finite_half(v[i]); }, nullptr, light));
        break;
      }
      case ValueFormat::kU8: {
        const std::uint8_t* c = q.codes.data();
        fn(row_sum(
            q, columns, [c](std::uint32_t i) { return static_cast<float>(c[i]); },
            q.row_scales.data(), light));
        break;
      }
    }
  };
  if (q.narrow_columns()) {
    by_columns(q.columns16.data());
  } else {
    by_columns(q.columns32.data());
  }
}

std::vector<Float4> light4(const QuantizedCsr& q, std::span<const Rgb> light, std::size_t out) {
  PRT_CHECK(light.size() == static_cast<std::size_t>(q.pixel_count) && out == q.rows(),
            "csr_quantized relight: light {} / output {} values for {} rows x {} columns",
            light.size(), out, q.rows(), q.pixel_count);
  std::vector<Float4> l4(light.size());
  for (std::size_t k = 0; k < light.size(); ++k)
    l4[k] = Float4{light[k].x, light[k].y, light[k].z, 0.f};
  return l4;
}

}  // namespace

void relight_quantized(const QuantizedCsr& q, std::span<const Rgb> light, std::span<Rgb> out) {
  const std::vector<Float4> l4 = light4(q, light, out.size());
  with_row_sum(q, l4.data(), [&](const auto& sum) {
    // 1024 rows per task, as prt::relight_exact: enough work per task, fine enough to balance.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, q.rows(), 1024), [&](const auto& r) {
      for (std::size_t row = r.begin(); row < r.end(); ++row) out[row] = sum(row);
    });
  });
}

void relight_quantized_vertices(const QuantizedCsr& q, std::span<const Rgb> light,
                                std::span<const std::uint32_t> vertices, std::span<Rgb> out) {
  const std::vector<Float4> l4 = light4(q, light, out.size());
  const auto m = static_cast<std::size_t>(q.local_count);
  with_row_sum(q, l4.data(), [&](const auto& sum) {
    // 16 vertices per task: 1024 rows at M = 64, as the full relight.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertices.size(), 16), [&](const auto& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i) {
        const std::size_t v = vertices[i];
        for (std::size_t j = 0; j < m; ++j) out[v * m + j] = sum(v * m + j);
      }
    });
  });
}

}  // namespace prt::csr_quantized
