#include "prtlab/compress/light_options.h"

namespace prt {

PointParams split_point_params(const CompressorEntry& entry,
                               const std::map<std::string, std::string>& params) {
  PointParams out;
  for (const auto& [k, v] : params) {
    bool light = false;
    for (const ParamSpec& s : entry.light_params) light = light || s.key == k;
    (light ? out.light : out.compression)[k] = v;
  }
  return out;
}

std::vector<ParamSpec> point_param_specs(const CompressorEntry& entry) {
  std::vector<ParamSpec> out = entry.params;
  out.insert(out.end(), entry.light_params.begin(), entry.light_params.end());
  return out;
}

std::map<std::string, std::string> canonical_light_options(
    const CompressorEntry& entry, const std::map<std::string, std::string>& light) {
  const auto& registry = CompressorRegistry::instance();
  const auto given = registry.light_options(entry.name, light).canonical();
  const auto defaults = registry.light_options(entry.name, {}).canonical();
  std::map<std::string, std::string> out;
  for (const auto& [k, v] : given)
    if (defaults.at(k) != v) out[k] = v;
  return out;
}

LightCoeffs project_light_with(const CompressedTransfer& ct, const Cubemap& radiance,
                               const std::map<std::string, std::string>& light_options) {
  if (light_options.empty()) return ct.project_light(radiance);
  return ct.project_light_under(
      radiance, CompressorRegistry::instance().light_options(ct.backend(), light_options));
}

}  // namespace prt
