#pragma once
// Uniformly distributed unit vectors for the tests (normalised Gaussian triples), seeded by the
// caller so that every failure can print its seed.
#include <glm/glm.hpp>
#include <random>

#include "prtlab/base/types.h"

namespace prt::testing {

inline Vec3d random_direction(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  for (;;) {
    const Vec3d v{g(rng), g(rng), g(rng)};
    const double len = glm::length(v);
    if (len > 1e-6) return v / len;
  }
}

}  // namespace prt::testing
