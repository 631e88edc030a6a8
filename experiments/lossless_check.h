#pragma once
// Is a compressed transfer an exact reconstruction of T? Checked through the public
// CompressedTransfer interface only (no backend headers), in two parts:
//
// 1. Count probes (exact). T's values are counts c in 0..s^2 times 1/s^2, and a row has at
//    most one entry per column. A probe light puts, in each colour channel, the weights
//    w_i = (s^2 + 1)^i on g distinct columns (0 elsewhere), so a row's output times s^2 is
//    the integer sum_i c_i w_i: the row's g counts written as base-(s^2 + 1) digits, decodable
//    exactly. g is the largest with (s^2 + 1)^g <= 4096, so every value stays far inside float
//    precision (s = 2: base 5, g = 5, 15 columns per probe, 410 probes for N = 6,144). The
//    probes cover every column once. The reference is relight_exact on the same light, which
//    is exact for these integer lights. A (row, channel, probe) output whose |s^2 (b - e)|
//    reaches 1/2 would decode to different counts: a mismatch. "Exact" means no mismatch
//    over all probes, i.e. every count of every row and column is reproduced (for digits in
//    0..s^2; a backend producing other values is caught by part 2). Needs a backend whose light
//    basis is the pixel basis (the probes are given as pixel-basis coefficients); others skip it.
// 2. Random non-negative lights: radiance uniform in [0, 1) per pixel and channel (seeded),
//    projected by the backend; the largest relative error of any output value against the
//    double-accumulated exact product (denominator: the exact value, floored at 1e-6 of the
//    largest exact value so empty rows count in absolute terms). A lossless backend stays at
//    float rounding (< kFloatRoundingBound); a dropped entry in a row of ~50 shows as ~1e-2.
//
// With an OpenCL context both parts run a second time through the backend's device relight
// (uploaded once), so a kernel that drops or misplaces a term is caught as surely as the C++
// path: the tables' "lossless" then covers the path the frame rates come from.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "prtlab/compress/compressor.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt::experiments {

/// Relative error a lossless relight may show from float output and accumulation.
inline constexpr double kFloatRoundingBound = 1e-5;

struct LosslessOptions {
  int random_lights = 4;
  std::uint64_t seed = 1;
  ClContext* device = nullptr;  ///< also check the OpenCL relight (null: C++ only)
};

/// The findings of parts 1 and 2 on one relight path (C++ or OpenCL).
struct LosslessPath {
  std::size_t probes = 0;          ///< relights used by part 1
  std::uint64_t probe_values = 0;  ///< (row, channel) outputs compared over all probes
  std::uint64_t mismatches = 0;    ///< of those, decoded to different counts
  /// max |s^2 (b - e)| over all probe outputs, in code units (0: bit-exact; a count off by one
  /// at digit i shows as (s^2 + 1)^i)
  double max_count_error = 0;
  double random_max_rel_error = 0;  ///< part 2
};

struct LosslessCheck {
  bool probe_applicable = false;  ///< the backend's light basis is the pixel basis
  int columns_per_probe = 0;      ///< 3 g
  int probe_weight_base = 0;      ///< s^2 + 1
  int random_lights = 0;
  std::uint64_t seed = 0;
  LosslessPath cpp;                    ///< the C++ relight
  std::optional<LosslessPath> opencl;  ///< the device relight, when a context was given
  std::string device;                  ///< its label ("" without one)

  /// On every path checked: part 1 found no mismatch (and ran) and part 2 stayed at float
  /// rounding.
  bool exact() const;
  /// "exact reconstruction" or a sentence saying what failed.
  std::string verdict() const;
};

LosslessCheck check_lossless(const CompressedTransfer& compressed, const TransferMatrix& t,
                             int cubemap_resolution, const LosslessOptions& options = {});

nlohmann::json to_json(const LosslessCheck& c);

}  // namespace prt::experiments
