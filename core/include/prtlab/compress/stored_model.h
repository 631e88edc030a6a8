#pragma once
// The stored model of a lossy compressed transfer, evaluated apart from its relight: an optional
// second interface a CompressedTransfer implements next to its own (a backend class derives from
// both; stored_model() finds it). It is kept out of CompressedTransfer so that backends and
// plugins that do not provide it are untouched (the plugin API stays as it is).
//
// model_radiance(light) is T~ L, the product of the backend's stored arrays (the decoded values
// relight() multiplies) with the light, in double and along another path than relight() (the
// rows of T~ rebuilt in the pixel basis and dotted with L, say, where relight() transforms the
// light first), at the local bins: an SH-output backend maps its coefficients to the bins with
// the cell integrals B of radiance_to_bins.h. `magnitude` is the same product over the absolute
// values of every factor and of the light, |T~|_factors |L|, the scale of the float rounding of
// any order of evaluation: a float relight that sums K terms per output differs from `values`
// by at most about K 2^-24 `magnitude` (at worst; sqrt(K) 2^-24 typically).
//
// The conformance suite holds relight() to it on every light it tries (the measured error
// against T L must be the model's own up to that rounding), so a lossy backend without a proven
// bound still has a finite, failing tolerance (docs/adding-a-compressor.md).
#include <vector>

#include "prtlab/base/types.h"
#include "prtlab/compress/compressor.h"
#include "prtlab/sphere/cubemap.h"

namespace prt {

struct ModelRadiance {
  std::vector<Vec3d> values;     ///< T~ L per row (vertex * M + j), pixel basis, RGB
  std::vector<Vec3d> magnitude;  ///< the same product over |factors| and |L| (>= |values|)
};

class StoredModel {
 public:
  virtual ~StoredModel();
  /// T~ L of the stored arrays for the light of `radiance` (non-negative or not), in double, and
  /// its magnitude; ParameterError for a cubemap of the wrong resolution.
  virtual ModelRadiance model_radiance(const Cubemap& radiance) const = 0;
};

/// The stored model `ct` provides, or nullptr when it provides none.
const StoredModel* stored_model(const CompressedTransfer& ct);

}  // namespace prt
