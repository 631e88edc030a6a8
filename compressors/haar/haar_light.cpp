// The non-linear approximation of the light (Ng 2003): rank the light's Haar coefficients by
// weight x |c| and keep the best ones (haar_light.h).
#include "haar/haar_light.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "haar/haar.h"
#include "haar/haar_wavelet.h"
#include "prtlab/base/error.h"

namespace prt::haar {

std::string_view to_string(LightWeight w) {
  switch (w) {
    case LightWeight::kSolidAngle:
      return "solid_angle";
    case LightWeight::kFaceArea:
      return "face_area";
    case LightWeight::kNone:
      return "none";
  }
  return "?";
}

LightWeight light_weight_from(std::string_view name) {
  for (LightWeight w : {LightWeight::kSolidAngle, LightWeight::kFaceArea, LightWeight::kNone})
    if (to_string(w) == name) return w;
  throw ParameterError(fmt::format(
      "{}: light weight '{}' is unknown (solid_angle, face_area or none)", kName, name));
}

std::vector<double> light_weights(const CubemapLayout& layout, LightWeight w) {
  const int r = layout.resolution();
  switch (w) {
    case LightWeight::kSolidAngle:
      return support_solid_angles(layout);  // checks R
    case LightWeight::kNone:
      if (!is_power_of_two(r))
        throw ParameterError(
            fmt::format("{}: the cubemap resolution R = {} is not a power of two", kName, r));
      return std::vector<double>(static_cast<std::size_t>(layout.pixel_count()), 1.0);
    case LightWeight::kFaceArea: {
      if (!is_power_of_two(r))
        throw ParameterError(
            fmt::format("{}: the cubemap resolution R = {} is not a power of two", kName, r));
      // A face is [-1, 1]^2: a pixel's face area is 4 / R^2 wherever it lies.
      const double pixel_area = 4.0 / (static_cast<double>(r) * r);
      std::vector<double> out(static_cast<std::size_t>(layout.pixel_count()));
      for (int f = 0; f < 6; ++f)
        for (int y = 0; y < r; ++y)
          for (int x = 0; x < r; ++x) {
            const int b = haar_support(r, x, y).size;
            out[layout.index(f, x, y)] = pixel_area * b * b;
          }
      return out;
    }
  }
  return {};
}

SparseLight truncate_light(std::span<const Rgb> coefficients, std::span<const double> weights,
                           std::size_t terms) {
  PRT_CHECK(coefficients.size() == weights.size(), "truncate_light: {} coefficients, {} weights",
            coefficients.size(), weights.size());
  struct Term {
    std::uint32_t index;
    double score;
  };
  std::vector<Term> candidates;
  candidates.reserve(coefficients.size());
  for (std::size_t k = 0; k < coefficients.size(); ++k) {
    const Rgb& c = coefficients[k];
    if (c.x == 0.f && c.y == 0.f && c.z == 0.f) continue;
    const double norm = std::sqrt(static_cast<double>(c.x) * c.x + static_cast<double>(c.y) * c.y +
                                  static_cast<double>(c.z) * c.z);
    candidates.push_back({static_cast<std::uint32_t>(k), weights[k] * norm});
  }
  if (terms > 0 && terms < candidates.size()) {
    const auto better = [](const Term& a, const Term& b) {
      return a.score != b.score ? a.score > b.score : a.index < b.index;
    };
    std::nth_element(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(terms),
                     candidates.end(), better);
    candidates.resize(terms);
    std::sort(candidates.begin(), candidates.end(),
              [](const Term& a, const Term& b) { return a.index < b.index; });
  }
  SparseLight out;
  out.indices.reserve(candidates.size());
  out.values.reserve(candidates.size());
  for (const Term& t : candidates) {
    out.indices.push_back(t.index);
    out.values.push_back(coefficients[t.index]);
  }
  return out;
}

LightCoeffs dense_light(const SparseLight& sparse, std::size_t pixels) {
  LightCoeffs out{std::string(kLightBasis), std::vector<Rgb>(pixels, Rgb(0.f, 0.f, 0.f))};
  for (std::size_t i = 0; i < sparse.indices.size(); ++i) {
    PRT_CHECK(sparse.indices[i] < pixels, "dense_light: index {} of N = {}", sparse.indices[i],
              pixels);
    out.values[sparse.indices[i]] = sparse.values[i];
  }
  return out;
}

SparseLight sparse_terms(std::span<const Rgb> coefficients) {
  SparseLight out;
  for (std::size_t k = 0; k < coefficients.size(); ++k) {
    const Rgb& c = coefficients[k];
    if (c.x == 0.f && c.y == 0.f && c.z == 0.f) continue;
    out.indices.push_back(static_cast<std::uint32_t>(k));
    out.values.push_back(c);
  }
  return out;
}

LightCoeffs approximate_light(std::span<const Rgb> pixel_light, const CubemapLayout& layout,
                              const LightApproximation& approximation) {
  const std::size_t n = static_cast<std::size_t>(layout.pixel_count());
  if (pixel_light.size() != n)
    throw ParameterError(
        fmt::format("{}: a light of {} pixel values for N = {}", kName, pixel_light.size(), n));
  std::vector<Rgb> w = transform_light(pixel_light, layout.resolution());
  if (approximation.terms == 0 || approximation.terms >= n)
    return {std::string(kLightBasis), std::move(w)};
  const std::vector<double> weights = light_weights(layout, approximation.weight);
  return dense_light(truncate_light(w, weights, approximation.terms), n);
}

}  // namespace prt::haar
