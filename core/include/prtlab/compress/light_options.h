#pragma once
// Run-time light options (CompressorEntry::light_params): parameters of a backend's light
// projection, such as Ng 2003's number of kept light terms, that change what a relight computes
// but not what was compressed. A point of an experiment carries them beside its compression
// parameters; this header splits the two and projects a light under the options.
#include <map>
#include <span>
#include <string>
#include <vector>

#include "prtlab/compress/compressor.h"
#include "prtlab/compress/compressor_registry.h"

namespace prt {

/// A point's parameters: what compress() takes and what project_light_under() takes.
struct PointParams {
  std::map<std::string, std::string> compression;
  std::map<std::string, std::string> light;
};

/// Splits `params` by the entry's light_params keys (every other key is a compression
/// parameter, validated later by whoever compresses).
PointParams split_point_params(const CompressorEntry& entry,
                               const std::map<std::string, std::string>& params);

/// The entry's params followed by its light_params: what an experiment point may set.
std::vector<ParamSpec> point_param_specs(const CompressorEntry& entry);

/// The light options whose canonical value differs from the default (an option left at its
/// default is the same point as one not given): the part of a point's key and report they add.
std::map<std::string, std::string> canonical_light_options(
    const CompressorEntry& entry, const std::map<std::string, std::string>& light);

/// `ct`'s projection of `radiance` under `light_options` (validated against its backend's
/// light_params: ParameterError listing them). No options: project_light(radiance).
LightCoeffs project_light_with(const CompressedTransfer& ct, const Cubemap& radiance,
                               const std::map<std::string, std::string>& light_options);

}  // namespace prt
