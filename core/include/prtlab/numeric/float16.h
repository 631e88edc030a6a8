#pragma once
// IEEE 754 binary16 ("half") conversion, for baselines that store values as 16-bit floats (a
// quantised CSR). Conversion to half rounds to nearest, ties to even, exactly like a hardware
// cvt: values beyond the largest half become infinity, tiny ones become subnormals or zero.
#include <cstdint>

namespace prt {

/// Round-to-nearest-even. A NaN stays a NaN with its sign and the top ten bits of its payload
/// (a payload that would become zero is made quiet instead, so it cannot turn into infinity).
std::uint16_t float_to_half(float value);

/// Exact: every half value is a float.
float half_to_float(std::uint16_t bits);

}  // namespace prt
