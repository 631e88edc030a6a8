#pragma once
// A seeded, non-negative RGB light of n pixel values for backend tests: a linear congruential
// generator (the same bits on every platform, unlike std distributions), channels in
// [0, 1), [0, green_scale) and [0.5, 1.5).
#include <cstdint>
#include <vector>

#include "prtlab/base/types.h"

namespace prt::testing {

inline std::vector<Rgb> pseudo_random_light(std::size_t n, std::uint64_t seed,
                                            float green_scale = 2.0f) {
  std::vector<Rgb> light(n);
  std::uint64_t x = seed;
  auto next = [&] {
    x = x * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<float>((x >> 40) & 0xffff) / 65536.0f;
  };
  for (auto& l : light) {
    const float r = next(), g = next(), b = next();
    l = Rgb(r, green_scale * g, 0.5f + b);
  }
  return light;
}

}  // namespace prt::testing
