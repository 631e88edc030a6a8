#pragma once
// Private to prtlab_core: stateless integer hashing for deterministic per-sample seeds and
// procedural lattice noise (the BTF generator and materials).
#include <cstdint>

namespace prt {

/// 32-bit finaliser (Wellons' "lowbias32" constants): every input bit affects every output bit.
inline std::uint32_t mix32(std::uint32_t v) {
  v ^= v >> 16;
  v *= 0x7feb352du;
  v ^= v >> 15;
  v *= 0x846ca68bu;
  v ^= v >> 16;
  return v;
}

/// Hash of a lattice point (Jarzynski & Olano 2020, PCG-style input combination).
inline std::uint32_t hash3(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  return mix32(((x * 1664525u + 1013904223u) + y * 22695477u) ^ (z * 2654435761u));
}

}  // namespace prt
