#pragma once
// The consistency checks every registry runs on a new entry's parameter declarations, so that a
// backend whose own specs are wrong fails at registration, not at first use.
#include <span>
#include <string>

#include "prtlab/compress/params.h"

namespace prt {

/// Throws prt::Error when a default is invalid or a key is declared twice among the parameters
/// (with the shared ones), the device options and the light options. `kind` ("compressor",
/// "material") prefixes the message.
void check_entry_params(const std::string& kind, const std::string& name,
                        std::span<const ParamSpec> params, std::span<const ParamSpec> device,
                        std::span<const ParamSpec> light = {});

}  // namespace prt
