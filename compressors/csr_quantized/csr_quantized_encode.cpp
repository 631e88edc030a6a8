// The quantisation of backend `csr_quantized`: T's values c / s^2 in the chosen format, and the
// exact error statistics of the stored values (max relative entry error, Frobenius error).
#include <algorithm>
#include <cmath>

#include "csr_quantized/csr_quantized.h"
#include "csr_quantized/half_decode.h"
#include "prtlab/numeric/float16.h"

namespace prt::csr_quantized {

std::size_t QuantizedCsr::value_bytes() const {
  switch (format) {
    case ValueFormat::kFloat32:
      return 4;
    case ValueFormat::kFloat16:
      return 2;
    case ValueFormat::kU8:
      return 1;
  }
  return 0;
}

QuantizedCsr quantize(const TransferMatrix& t, ValueFormat format) {
  QuantizedCsr q;
  q.vertices = t.vertex_count();
  q.local_count = t.local_count();
  q.pixel_count = static_cast<int>(t.cols());
  q.format = format;
  q.offsets.assign(t.row_offsets().begin(), t.row_offsets().end());
  if (t.narrow_columns()) {
    q.columns16.assign(t.columns16().begin(), t.columns16().end());
  } else {
    q.columns32.assign(t.columns32().begin(), t.columns32().end());
  }
  const auto counts = t.counts();
  const double unit = t.scale();
  double max_error = 0, diff2 = 0, norm2 = 0;
  // Accumulates one stored entry of exact value c * unit.
  auto account = [&](std::uint8_t c, double stored) {
    const double exact = c * unit;
    const double d = stored - exact;
    max_error = std::max(max_error, std::abs(d) / exact);
    diff2 += d * d;
    norm2 += exact * exact;
  };
  switch (format) {
    case ValueFormat::kFloat32:
      q.values32.resize(t.nnz());
      for (std::size_t i = 0; i < t.nnz(); ++i) {
        q.values32[i] = static_cast<float>(counts[i] * unit);
        account(counts[i], q.values32[i]);
      }
      break;
    case ValueFormat::kFloat16:
      q.values16.resize(t.nnz());
      for (std::size_t i = 0; i < t.nnz(); ++i) {
        q.values16[i] = float_to_half(static_cast<float>(counts[i] * unit));
        account(counts[i], decode_finite_half(q.values16[i]));
      }
      break;
    case ValueFormat::kU8:
      q.codes.resize(t.nnz());
      q.row_scales.resize(t.rows());
      for (std::size_t row = 0; row < t.rows(); ++row) {
        const std::uint32_t begin = q.offsets[row], end = q.offsets[row + 1];
        const int cmax =
            begin == end ? 0 : *std::max_element(counts.begin() + begin, counts.begin() + end);
        // An empty row keeps scale 0: it multiplies an empty sum.
        const float scale = static_cast<float>(cmax * unit / 255.0);
        q.row_scales[row] = scale;
        for (std::uint32_t i = begin; i < end; ++i) {
          // round(c * 255 / cmax) in integers, halves up: v / scale_row without the float
          // rounding of scale_row deciding a tie.
          const int code = (510 * counts[i] + cmax) / (2 * cmax);
          q.codes[i] = static_cast<std::uint8_t>(code);
          account(counts[i], static_cast<double>(code) * static_cast<double>(scale));
        }
      }
      break;
  }
  q.max_entry_error = max_error;
  q.frobenius_error = norm2 > 0 ? std::sqrt(diff2 / norm2) : 0.0;
  return q;
}

}  // namespace prt::csr_quantized
