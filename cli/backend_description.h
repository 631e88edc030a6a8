#pragma once
// A registered backend described as data: the JSON of `prtlab list --json` and the Markdown
// block of `prtlab list --markdown NAME`, which scripts/gen_backend_docs.py writes into the
// backend's README (so the parameter tables there are the registry's, never retyped).
#include <nlohmann/json.hpp>
#include <string>

#include "prtlab/compress/compressor_registry.h"

namespace prt::cli {

/// key, type, default, doc, and min, max, choices where declared.
nlohmann::json param_spec_json(const ParamSpec& spec);

/// name, description, lossless, origin, inputs, output_basis, size_knob (null when none),
/// parameters, device_parameters.
nlohmann::json backend_json(const CompressorEntry& entry);

/// "error (larger is less storage; 0.001 to 1, log scale)", or "none".
std::string size_knob_summary(const CompressorEntry& entry);

/// The Markdown that stands between `<!-- params:begin -->` and `<!-- params:end -->` in the
/// backend's README: a table of every parameter (its own, the shared ones, the device
/// options), its size knob, output basis and inputs. Ends with a newline.
std::string backend_markdown(const CompressorEntry& entry);

}  // namespace prt::cli
