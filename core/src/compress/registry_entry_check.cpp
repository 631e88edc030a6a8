#include "compress/registry_entry_check.h"

#include <fmt/format.h>

#include <map>

#include "prtlab/base/error.h"

namespace prt {

void check_entry_params(const std::string& kind, const std::string& name,
                        std::span<const ParamSpec> params, std::span<const ParamSpec> device,
                        std::span<const ParamSpec> light) {
  const ParamSet validate(name, params, {});
  const ParamSet validate_device(name + " (device options)", device, {},
                                 ParamSet::Shared::kExclude);
  const ParamSet validate_light(name + " (light options)", light, {}, ParamSet::Shared::kExclude);
  (void)validate;
  (void)validate_device;
  (void)validate_light;
  std::map<std::string, std::string> declared;  // key -> what declared it first
  const auto claim = [&](std::span<const ParamSpec> specs, const char* what) {
    for (const auto& s : specs)
      if (const auto [it, fresh] = declared.emplace(s.key, what); !fresh)
        throw Error(fmt::format("{} registry: '{}' declares '{}' both as {} and as {}", kind, name,
                                s.key, it->second, what));
  };
  claim(shared_param_specs(), "a shared parameter");
  claim(params, "a parameter");
  claim(device, "a device option");
  claim(light, "a light option");
}

}  // namespace prt
