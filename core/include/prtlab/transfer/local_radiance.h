#pragma once
// Per-vertex local incident radiance L*_p = T_p L, in the basis the backend produces.
#include <cstddef>
#include <span>
#include <string_view>
#include <vector>

#include "prtlab/base/types.h"

namespace prt {

enum class RadianceBasis {
  kPixel,               ///< M values per vertex: the local hemisphere grid cells d_j
  kSphericalHarmonics,  ///< n = order^2 SH coefficients per vertex, in the local frame
};
std::string_view to_string(RadianceBasis b);

struct LocalRadiance {
  RadianceBasis basis = RadianceBasis::kPixel;
  int dim = 0;  ///< values per vertex (M, or n SH coefficients)
  std::size_t vertices = 0;
  std::vector<Rgb> values;  ///< vertices * dim, index = vertex * dim + j

  LocalRadiance() = default;
  LocalRadiance(RadianceBasis b, int d, std::size_t v)
      : basis(b), dim(d), vertices(v), values(static_cast<std::size_t>(d) * v, Rgb(0.f)) {}
  /// Makes this a zero-filled radiance of that shape unless it already has it; then its values
  /// stay, so a relight of a vertex subset leaves the other vertices as they were.
  void ensure_shape(RadianceBasis b, int d, std::size_t v) {
    if (basis != b || dim != d || vertices != v || values.size() != static_cast<std::size_t>(d) * v)
      *this = LocalRadiance(b, d, v);
  }
  std::size_t rows() const { return values.size(); }
  std::span<const Rgb> vertex(std::size_t v) const {
    return std::span<const Rgb>(values).subspan(v * static_cast<std::size_t>(dim),
                                                static_cast<std::size_t>(dim));
  }
};

/// Relative L2 error ||a - b|| / ||b|| over all values and channels (b is the reference);
/// NaN with the "zero-reference" warning when b is zero (base/relative_error.h). Throws when
/// the shapes differ.
double relative_l2_error(const LocalRadiance& a, const LocalRadiance& reference);
/// Relative L1 error sum |a - b| / sum |b| over all values and channels (NaN for b = 0).
double relative_l1_error(const LocalRadiance& a, const LocalRadiance& reference);
/// Values with a NaN or infinite channel: a relight that overflowed float, or bad input.
std::size_t count_nonfinite(std::span<const Rgb> values);
/// Largest |a - b| over values and channels, divided by the largest |b| (max-norm error).
double max_relative_error(const LocalRadiance& a, const LocalRadiance& reference);

}  // namespace prt
