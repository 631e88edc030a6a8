#pragma once
// IEEE half -> float for finite halves, inline so that the relight's inner loop converts in a few
// instructions (prt::half_to_float is an out-of-line call, and this build targets no F16C).
// Moving the 15 exponent and mantissa bits into float position gives a float 2^-112 times the
// half's magnitude for normal and subnormal halves alike; the multiply by 2^112 is exact. Infinity
// and NaN (exponent 31) would come out finite: load() refuses them, quantize() never makes them.
#include <bit>
#include <cstdint>

namespace prt::csr_quantized {

inline float decode_finite_half(std::uint16_t half) {
  const std::uint32_t magnitude = static_cast<std::uint32_t>(half & 0x7fffu) << 13;
  const float value = std::bit_cast<float>(magnitude) * 0x1p112f;
  const std::uint32_t sign = static_cast<std::uint32_t>(half & 0x8000u) << 16;
  return std::bit_cast<float>(std::bit_cast<std::uint32_t>(value) | sign);
}

/// Whether `half` is finite (exponent below 31), i.e. decode_finite_half is exact for it.
inline bool is_finite_half(std::uint16_t half) {
  return (half & 0x7c00u) != 0x7c00u;
}

}  // namespace prt::csr_quantized
