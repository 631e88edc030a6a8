#pragma once
// Measuring a compressed transfer against the exact product: the numbers every report prints.
//
// Error: relative L2 of L* (all rows, RGB) vs the exact CSR product accumulated in double, per
// light; the summary is the mean and the maximum over the light set. Also the relative
// Frobenius error ||T~ - T||_F / ||T||_F and the largest per-vertex relative error
// (transfer_error.h). A backend relighting into another basis (SH) is compared at the local
// bins (to_pixel_basis). Lights: the 8 Blender
// world maps when the data cache has them, else procedural sun-and-sky variants.
// Time: median over `repeats` relights, C++ (wall) and OpenCL (kernel time from events).
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "prtlab/compress/compressor.h"
#include "prtlab/compress/transfer_error.h"
#include "prtlab/sphere/cubemap.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt {

struct EvaluationLight {
  std::string name;
  Cubemap radiance;
};

/// The evaluation light set at cubemap resolution R (names "courtyard", ... or "sunsky-N").
/// `limit` > 0 keeps the first `limit` lights.
std::vector<EvaluationLight> evaluation_lights(int resolution, int limit = 0);

struct LightError {
  std::string light;
  double rel_l2 = 0;
  double max_rel = 0;  ///< max-norm error relative to the largest exact value
};

struct BackendEvaluation {
  std::vector<LightError> errors;
  double mean_rel_l2 = 0;
  double max_rel_l2 = 0;
  FrobeniusError frobenius;         ///< ||T~ - T||_F / ||T||_F (exact or estimated, see its fields)
  double max_vertex_rel = 0;        ///< largest per-vertex relative error over the lights
  std::size_t worst_vertex = 0;     ///< where it occurs
  double ms_cpp = 0;                ///< median C++ relight (light projection excluded)
  double ms_project = 0;            ///< median light projection
  std::optional<double> ms_opencl;  ///< median kernel time; empty without a device
  std::optional<double> opencl_vs_cpp;  ///< relative L2 of OpenCL vs C++ output
  std::string device;                   ///< device label, or "none"
};

struct EvaluationOptions {
  int repeats = 20;                                   ///< relights timed (medians reported)
  std::map<std::string, std::string> device_options;  ///< the backend's device_params
  /// The backend's light_params (light_options.h): every light of the evaluation is projected
  /// under them. The Frobenius error stays that of T~ (its probe lights are not approximated).
  std::map<std::string, std::string> light_options;
  /// Relights spent on the Frobenius error: exact when N / 3 fits, else Hutchinson's estimate;
  /// 0 skips it (frobenius stays zero with relights = 0).
  int frobenius_relights = 64;
  std::uint64_t seed = 1;  ///< of the Frobenius estimate
};

/// Float rounding allowed on top of a declared bound: a float sum of k positive terms is within
/// k * 2^-24 relative, and rows of the scenes here have at most a few hundred terms.
inline constexpr double kFloatRoundingTolerance = 1e-5;

/// Throws a NumericalError when `approx` (the backend's relight, in the pixel basis) has a
/// non-finite value or differs from `exact` by more than the backend's declared bound (plus
/// kFloatRoundingTolerance) in its declared norm: a report must not print such a number.
void check_within_declared_bound(const CompressedTransfer& ct, const LocalRadiance& approx,
                                 const LocalRadiance& exact, const std::string& light);

/// Evaluate `ct` on `lights` (error per light vs the exact product with `exact`), timing the
/// first light's relight `repeats` times. Throws check_within_declared_bound()'s NumericalError.
/// `context` may be null (no OpenCL).
BackendEvaluation evaluate_backend(const CompressedTransfer& ct, const TransferMatrix& exact,
                                   const std::vector<EvaluationLight>& lights, ClContext* context,
                                   const EvaluationOptions& options = {});

}  // namespace prt
