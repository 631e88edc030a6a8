#include "backend_description.h"

#include <fmt/format.h>

namespace prt::cli {
namespace {

std::string number(double v, ParamType type) {
  return type == ParamType::kInt ? fmt::format("{}", static_cast<long long>(v))
                                 : fmt::format("{}", v);
}

std::string range_text(const ParamSpec& s) {
  switch (s.type) {
    case ParamType::kInt:
    case ParamType::kReal:
      if (!s.min && !s.max) return "any";
      return fmt::format("{} to {}", s.min ? number(*s.min, s.type) : "-inf",
                         s.max ? number(*s.max, s.type) : "inf");
    case ParamType::kBool:
      return "`true`, `false`";
    case ParamType::kString:
    case ParamType::kEnum:
      break;
  }
  if (s.choices.empty()) return "any";
  std::string out;
  for (const auto& c : s.choices) out += (out.empty() ? "`" : ", `") + c + "`";
  return out;
}

// A pipe inside a cell would end it.
std::string cell(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '|') out += '\\';
    out += c;
  }
  return out;
}

std::string table_row(const ParamSpec& s, std::string_view tag) {
  return fmt::format("| `{}`{} | {} | {} | {} | {} |\n", s.key, tag, to_string(s.type),
                     cell(s.default_value), cell(range_text(s)), cell(s.doc));
}

std::string inputs_summary(const BackendInputs& in) {
  std::string out;
  auto add = [&](const std::string& what) { out += (out.empty() ? "" : ", ") + what; };
  if (in.sh_order > 0) add(fmt::format("the SH transfer of order {}", in.sh_order));
  if (in.mesh) add("the mesh");
  if (in.btfs) add("the BTFs");
  if (in.brdf_signal)
    add("the BRDF-weighted signal (`signal=brdf`; its parameters `brdf_*` come with it)");
  return out.empty() ? "none" : out;
}

const ParamSpec* find_spec(const CompressorEntry& e, const std::string& key) {
  for (const auto& s : e.params)
    if (s.key == key) return &s;
  return nullptr;
}

// "(larger is less storage; 0.001 to 1, log scale)": the range in the parameter's own type.
std::string knob_detail(const CompressorEntry& e) {
  const SizeKnob& k = *e.size_knob;
  const ParamSpec* spec = find_spec(e, k.key);
  const ParamType type = spec ? spec->type : ParamType::kReal;
  return fmt::format("(larger is {} storage; {} to {}, {} scale)",
                     k.direction == SizeKnob::Direction::kLargerIsMoreStorage ? "more" : "less",
                     number(k.min.value(), type), number(k.max.value(), type),
                     k.scale == SizeKnob::Scale::kLog ? "log" : "linear");
}

}  // namespace

nlohmann::json param_spec_json(const ParamSpec& s) {
  nlohmann::json j{{"key", s.key},
                   {"type", std::string(to_string(s.type))},
                   {"default", s.default_value},
                   {"doc", s.doc}};
  if (s.min) j["min"] = *s.min;
  if (s.max) j["max"] = *s.max;
  if (!s.choices.empty()) j["choices"] = s.choices;
  return j;
}

nlohmann::json backend_json(const CompressorEntry& e) {
  nlohmann::json params = nlohmann::json::array(), device = nlohmann::json::array(),
                 light = nlohmann::json::array();
  for (const auto& s : e.params) params.push_back(param_spec_json(s));
  for (const auto& s : e.device_params) device.push_back(param_spec_json(s));
  for (const auto& s : e.light_params) light.push_back(param_spec_json(s));
  nlohmann::json knob = nullptr;
  if (e.size_knob)
    knob = {{"key", e.size_knob->key},
            {"direction", std::string(to_string(e.size_knob->direction))},
            {"min", e.size_knob->min.value()},
            {"max", e.size_knob->max.value()},
            {"scale", std::string(to_string(e.size_knob->scale))}};
  return {{"name", e.name},
          {"description", e.description},
          {"lossless", e.lossless},
          {"origin", e.origin},
          {"inputs",
           {{"sh_order", e.inputs.sh_order},
            {"mesh", e.inputs.mesh},
            {"btfs", e.inputs.btfs},
            {"brdf_signal", e.inputs.brdf_signal}}},
          {"output_basis", std::string(to_string(e.output_basis))},
          {"size_knob", knob},
          {"parameters", params},
          {"device_parameters", device},
          {"light_parameters", light}};
}

std::string size_knob_summary(const CompressorEntry& e) {
  return e.size_knob ? e.size_knob->key + " " + knob_detail(e) : "none";
}

std::string backend_markdown(const CompressorEntry& e) {
  std::string out = fmt::format(
      "<!-- generated from `prtlab list --markdown {}`: edit the registry entry, then run "
      "python3 scripts/gen_backend_docs.py -->\n\n",
      e.name);
  out += "| parameter | type | default | range | meaning |\n|---|---|---|---|---|\n";
  for (const auto& s : e.params) out += table_row(s, "");
  for (const auto& s : shared_param_specs()) out += table_row(s, " (shared)");
  for (const auto& s : e.device_params) out += table_row(s, " (device)");
  for (const auto& s : e.light_params) out += table_row(s, " (light)");
  out += "\n";
  out += e.size_knob ? fmt::format("- **size knob:** `{}` {}\n", e.size_knob->key, knob_detail(e))
                     : "- **size knob:** none (the storage does not depend on the parameters)\n";
  out += fmt::format("- **output basis:** {}\n", to_string(e.output_basis));
  out += fmt::format("- **inputs besides T:** {}\n", inputs_summary(e.inputs));
  out += "\n(shared: every backend accepts it";
  if (!e.device_params.empty())
    out += "; device: an option of the OpenCL path, `--device-param`, never recompresses";
  if (!e.light_params.empty())
    out +=
        "; light: an option of the light projection at run time, `--light-param` or a point's "
        "parameter in an experiment, changes the relight but never recompresses";
  out += ".)\n";
  return out;
}

}  // namespace prt::cli
