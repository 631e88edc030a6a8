#pragma once
// The accuracy checks of the conformance suite, as functions: the suite (conformance_test.cpp)
// and the test that the checks reject a perturbed backend (lossy_perturbation_test.cpp) call the
// same code.
//
//   relight_within_declaration   one light: relight (at the bins) against the exact T L
//     - a finite declared_error_bound(): the error in the declared norm within it (a lossless
//       result declares 0 and gets kLosslessTolerance, as relative L2 and as max-norm error);
//     - a stored model (stored_model.h): relight() equals the model's T~ L up to float rounding,
//       ||relight - T~ L|| <= kModelRounding ||magnitude|| + kTiny, so the measured error
//       ||relight - T L|| / ||T L|| is the declared ||T~ L - T L|| / ||T L|| within that;
//     - neither, but an expected Frobenius error e_F: the operator-norm bound
//       ||T~ L - T L|| <= e_F ||T||_F ||L||_F, which holds for every light;
//     - none of these: a failure (no finite tolerance exists).
//   frobenius_within_declaration   the measured ||T~ - T||_F / ||T||_F (transfer_error.h):
//     - lossless: within kLosslessTolerance;
//     - a declared expected_frobenius_error() and a stored model, every column probed: the
//       declared value is the model's own, probed column by column through model_radiance()
//       (kDeclaredTolerance: two double computations of one number); every relit column is the
//       model's, ||T~_relit - T~_model||_F <= kModelRounding ||magnitude||_F; and so the
//       measured value is the declared one within that distance over ||T||_F;
//     - a declared value otherwise (no model, or Hutchinson's estimate on a wide case): within
//       1e-3 relative plus four standard errors of the estimate;
//     - a lossy backend without a proven bound that declares no Frobenius error: a failure.
//
// Tolerances. A float sum of K terms differs from the exact sum by at most about K 2^-24 times
// the sum of the terms' magnitudes (sqrt(K) 2^-24 for rounding errors of random sign); the
// relights sum at most a few hundred terms per output in float (a representative's dot with L
// in 64 lanes of N / 64 terms, then short blends), so kModelRounding = 1e-5 per unit of the
// magnitude holds them with margin and still sees a 1 % change of any relight whose magnitude is
// within a factor 1,000 of its value.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <string>

#include "prtlab/compress/compressor.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/stored_model.h"
#include "prtlab/compress/transfer_error.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/transfer/radiance_to_bins.h"
#include "support/synthetic_cases.h"

namespace prt::conformance {

// Float rounding of a sum of k positive terms is below k * 2^-24 relative; the cases have rows
// of at most ~100 terms, so 1e-6 leaves margin without hiding a wrong term (a single wrong count
// among 100 is an error of about 1e-2).
inline constexpr double kLosslessTolerance = 1e-6;
/// relight vs the stored model, per unit of the model's magnitude (see above).
inline constexpr double kModelRounding = 1e-5;
/// The declared Frobenius error vs the model probed column by column: both double.
inline constexpr double kDeclaredTolerance = 1e-6;
/// Below any radiance the cases produce; keeps an all-zero T's check at exact zeros.
inline constexpr double kTiny = 1e-30;
/// The relights frobenius_error() may spend per case (512 covers N <= 1,536; wider cases are
/// estimated from 16 relights).
inline constexpr int kFrobeniusExactRelights = 512;
inline constexpr int kFrobeniusEstimateRelights = 16;

namespace accuracy_detail {

inline double norm(const std::vector<Vec3d>& a) {
  double s = 0;
  for (const Vec3d& v : a) s += glm::dot(v, v);
  return std::sqrt(s);
}

inline double distance(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b) {
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const Vec3d d = a[i] - b[i];
    s += glm::dot(d, d);
  }
  return std::sqrt(s);
}

inline std::vector<Vec3d> as_double(const LocalRadiance& r) {
  std::vector<Vec3d> out(r.values.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = Vec3d(r.values[i]);
  return out;
}

inline LocalRadiance as_float(const std::vector<Vec3d>& d, const CaseData& c) {
  LocalRadiance out(RadianceBasis::kPixel, c.transfer.local_count(), c.transfer.vertex_count());
  for (std::size_t i = 0; i < d.size(); ++i) out.values[i] = Rgb(d[i]);
  return out;
}

inline double frobenius_norm(const TransferMatrix& t) {
  double s = 0;
  for (std::size_t e = 0; e < t.nnz(); ++e) s += std::pow(t.counts()[e] * t.scale(), 2);
  return std::sqrt(s);
}

// The unit light of columns first .. first + 2 (one per channel), as frobenius_error() builds it.
inline Cubemap unit_light(int resolution, std::size_t first, std::size_t n) {
  Cubemap light(resolution);
  for (int ch = 0; ch < 3 && first + ch < n; ++ch) {
    const int k = static_cast<int>(first) + ch;
    light.radiance[static_cast<std::size_t>(k)][ch] =
        static_cast<float>(1.0 / light.layout.solid_angle(k));
  }
  return light;
}

}  // namespace accuracy_detail

/// Relight of `light` by `ct` (the entry's backend, compressed from `c`) against T L, within what
/// the backend declares (see the header comment).
inline ::testing::AssertionResult relight_within_declaration(const CompressedTransfer& ct,
                                                             const CompressorEntry& entry,
                                                             const CaseData& c,
                                                             const Cubemap& light) {
  using namespace accuracy_detail;
  LocalRadiance raw;
  ct.relight(ct.project_light(light), raw);
  // Any output basis is compared at the local bins (to_pixel_basis).
  const LocalRadiance out = to_pixel_basis(raw, c.grid);
  if (out.basis != RadianceBasis::kPixel || out.dim != c.transfer.local_count() ||
      out.vertices != c.transfer.vertex_count() || out.values.size() != c.transfer.rows())
    return ::testing::AssertionFailure()
           << "relight has " << out.values.size() << " values (" << out.vertices << " x " << out.dim
           << "), T has " << c.transfer.rows() << " rows";
  const std::vector<Vec3d> exact = relight_exact_double(c.transfer, light.light_vector());
  const std::vector<Vec3d> got = as_double(out);
  const double exact_norm = norm(exact);
  const double measured = distance(got, exact) / std::max(exact_norm, kTiny);
  const double bound = ct.declared_error_bound();
  if (!(bound >= 0 && (std::isfinite(bound) || bound == kNoErrorBound)))
    return ::testing::AssertionFailure() << "declared_error_bound " << bound;
  if (entry.lossless && bound != 0)
    return ::testing::AssertionFailure()
           << "a lossless backend declares a bound of 0, not " << bound;
  if (c.transfer.nnz() == 0) {
    for (const Rgb& v : out.values)
      if (v != Rgb(0.f))
        return ::testing::AssertionFailure() << "an all-zero T must relight to exact zeros";
  }
  const LocalRadiance reference = as_float(exact, c);
  if (std::isfinite(bound)) {
    const double tolerance =
        bound == 0 ? kLosslessTolerance : bound * (1 + 1e-6) + kLosslessTolerance;
    const double e = ct.declared_error_norm() == CompressedTransfer::ErrorNorm::kRelativeL1
                         ? relative_l1_error(out, reference)
                         : relative_l2_error(out, reference);
    if (e > tolerance)
      return ::testing::AssertionFailure() << to_string(ct.declared_error_norm()) << " error " << e
                                           << " > the declared bound's tolerance " << tolerance;
    if (bound == 0) {
      const double l2 = relative_l2_error(out, reference), mx = max_relative_error(out, reference);
      if (l2 > kLosslessTolerance || mx > kLosslessTolerance)
        return ::testing::AssertionFailure()
               << "lossless: relative L2 error " << l2 << ", max-norm error " << mx << " > "
               << kLosslessTolerance;
    }
  }
  if (const StoredModel* model = stored_model(ct)) {
    const ModelRadiance m = model->model_radiance(light);
    if (m.values.size() != got.size() || m.magnitude.size() != got.size())
      return ::testing::AssertionFailure()
             << "the stored model has " << m.values.size() << " values, the relight " << got.size();
    const double off = distance(got, m.values), scale = norm(m.magnitude);
    const double declared = distance(m.values, exact) / std::max(exact_norm, kTiny);
    const double tolerance = kModelRounding * scale + kTiny;
    if (!(off <= tolerance))
      return ::testing::AssertionFailure()
             << "relight differs from the backend's stored model T~ L by " << off << " (L2; "
             << off / std::max(norm(m.values), kTiny) << " of ||T~ L||) > " << tolerance << " = "
             << kModelRounding << " x the model's magnitude " << scale
             << ": measured error against T L " << measured << ", declared (the model's) "
             << declared;
    return ::testing::AssertionSuccess() << "measured " << measured << ", declared " << declared;
  }
  if (std::isfinite(bound)) return ::testing::AssertionSuccess() << "measured " << measured;
  const std::optional<double> frobenius = ct.expected_frobenius_error();
  if (!frobenius)
    return ::testing::AssertionFailure()
           << "no finite tolerance: the backend declares no error bound, no stored model and no "
              "expected Frobenius error";
  // ||(T~ - T) L_ch|| <= ||T~ - T||_2 ||L_ch|| <= e_F ||T||_F ||L_ch|| per channel.
  double light_sq = 0;
  for (const Rgb& l : light.light_vector()) light_sq += glm::dot(Vec3d(l), Vec3d(l));
  const double limit = *frobenius * frobenius_norm(c.transfer) * std::sqrt(light_sq) * (1 + 1e-6) +
                       kLosslessTolerance * exact_norm + kTiny;
  const double absolute = distance(got, exact);
  if (absolute > limit)
    return ::testing::AssertionFailure()
           << "||relight - T L|| = " << absolute << " > e_F ||T||_F ||L||_F = " << limit
           << " (e_F = " << *frobenius << ")";
  return ::testing::AssertionSuccess() << "measured " << measured;
}

/// The measured relative Frobenius error of `ct` against what it declares (see above).
/// `measured_out`, when given, receives the measurement.
inline ::testing::AssertionResult frobenius_within_declaration(
    const CompressedTransfer& ct, const CompressorEntry& entry, const CaseData& c,
    FrobeniusError* measured_out = nullptr) {
  using namespace accuracy_detail;
  const FrobeniusError f =
      frobenius_error(ct, c.transfer, c.grid, kFrobeniusExactRelights, kFrobeniusEstimateRelights);
  if (measured_out != nullptr) *measured_out = f;
  // For T = 0 the relative error is undefined (NaN, base/relative_error.h); the checks then hold
  // the absolute ||T~ - T||_F to the same numbers (the scale convention below).
  const double relative = frobenius_norm(c.transfer) > 0 ? f.relative : f.absolute;
  const double slack = f.exact ? 0.0 : 4.0 * f.standard_error;
  if (entry.lossless && relative > kLosslessTolerance + slack)
    return ::testing::AssertionFailure()
           << "lossless, but the measured Frobenius error is " << relative;
  const std::optional<double> expected = ct.expected_frobenius_error();
  if (!expected) {
    if (!entry.lossless && !std::isfinite(ct.declared_error_bound()))
      return ::testing::AssertionFailure()
             << "a lossy backend without a proven bound declares no expected Frobenius error "
                "(measured "
             << relative << ")";
    return ::testing::AssertionSuccess() << "measured " << relative;
  }
  if (!(std::isfinite(*expected) && *expected >= 0))
    return ::testing::AssertionFailure() << "expected_frobenius_error " << *expected;
  const StoredModel* model = stored_model(ct);
  if (model != nullptr && f.exact) {
    // The model and the relight probed with frobenius_error()'s own unit lights, column by
    // column: the relit T~ must be the model's (first order in any change of the relight, where
    // the norms' difference is second order for a fit whose residual is orthogonal to T~).
    const std::size_t n = c.transfer.cols();
    const int resolution = c.cubemap.resolution();
    double diff_sq = 0, off_sq = 0, magnitude_sq = 0;
    for (std::size_t first = 0; first < n; first += 3) {
      const Cubemap light = unit_light(resolution, first, n);
      const ModelRadiance m = model->model_radiance(light);
      const std::vector<Vec3d> exact = relight_exact_double(c.transfer, light.light_vector());
      LocalRadiance raw;
      ct.relight(ct.project_light(light), raw);
      const std::vector<Vec3d> got = as_double(to_pixel_basis(raw, c.grid));
      if (m.values.size() != exact.size() || got.size() != exact.size())
        return ::testing::AssertionFailure()
               << "the stored model has " << m.values.size() << " values, the relight "
               << got.size() << ", T " << exact.size() << " rows";
      const double d = distance(m.values, exact), o = distance(got, m.values),
                   s = norm(m.magnitude);
      diff_sq += d * d;
      off_sq += o * o;
      magnitude_sq += s * s;
    }
    const double t_norm = frobenius_norm(c.transfer);
    const double scale = t_norm > 0 ? t_norm : 1.0;  // frobenius_error's convention for T = 0
    const double model_error = std::sqrt(diff_sq) / scale;
    if (std::abs(*expected - model_error) > kDeclaredTolerance * (1 + *expected))
      return ::testing::AssertionFailure()
             << "the declared expected_frobenius_error() " << *expected
             << " is not the stored model's, probed column by column: " << model_error;
    const double off = std::sqrt(off_sq), tolerance = kModelRounding * std::sqrt(magnitude_sq);
    if (!(off <= tolerance + kTiny))
      return ::testing::AssertionFailure()
             << "the relit T~ differs from the stored model's by " << off << " = " << off / scale
             << " ||T||_F (every column probed) > " << tolerance << " = " << kModelRounding
             << " x ||magnitude||_F; measured Frobenius error " << relative << ", declared "
             << *expected;
    // |measured - model| <= ||T~_relit - T~_model||_F / ||T||_F (triangle inequality).
    if (!(std::abs(relative - model_error) <= (off / scale) * (1 + 1e-6) + 1e-12))
      return ::testing::AssertionFailure()
             << "measured Frobenius error " << relative << " vs the stored model's " << model_error
             << " (declared " << *expected << "): differ by more than the relit "
             << "columns' distance to the model, " << off / scale;
    return ::testing::AssertionSuccess() << "measured " << relative << ", declared " << *expected;
  }
  const double tolerance = 1e-3 * *expected + kLosslessTolerance + slack;
  if (std::abs(relative - *expected) > tolerance)
    return ::testing::AssertionFailure()
           << "measured Frobenius error " << relative << (f.exact ? " (exact)" : " (estimated)")
           << " vs the backend's expected_frobenius_error() " << *expected << ": differ by more "
           << "than " << tolerance;
  return ::testing::AssertionSuccess() << "measured " << relative << ", declared " << *expected;
}

}  // namespace prt::conformance
