#pragma once
// Which cube faces of a pixel-basis light carry energy. Faces are contiguous column ranges of T
// (pixel k = face * R^2 + ..., cubemap.h), so a backend can skip the columns of a dark face:
// their terms are count * 0 = 0, and adding +0 or -0 to a float sum that starts at +0 leaves
// it unchanged bit for bit, so skipping them is exact, not an approximation.
#include <cstdint>
#include <span>

#include "prtlab/base/types.h"

namespace prt {

inline constexpr int kCubeFaces = 6;
/// Every face lit: bits 0..5.
inline constexpr std::uint32_t kAllFaces = (1u << kCubeFaces) - 1;

/// Bit f set when face f of `light` (N = 6 R^2 values in cubemap order) holds a value that is
/// not zero in some channel (NaN counts as lit). kAllFaces when N is not a multiple of 6, so a
/// caller never skips anything it cannot place.
std::uint32_t lit_faces(std::span<const Rgb> light);

}  // namespace prt
