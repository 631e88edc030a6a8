#include "compress/registry_entry_check.h"

#include <fmt/format.h>

#include "prtlab/base/error.h"

namespace prt {

void check_entry_params(const std::string& kind, const std::string& name,
                        std::span<const ParamSpec> params, std::span<const ParamSpec> device) {
  const ParamSet validate(name, params, {});
  const ParamSet validate_device(name + " (device options)", device, {},
                                 ParamSet::Shared::kExclude);
  (void)validate;
  (void)validate_device;
  for (const auto& d : device)
    for (const auto& p : params)
      if (d.key == p.key)
        throw Error(fmt::format(
            "{} registry: '{}' declares '{}' both as a parameter and as a device option", kind,
            name, d.key));
}

}  // namespace prt
