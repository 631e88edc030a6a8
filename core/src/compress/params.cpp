#include "prtlab/compress/params.h"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "prtlab/base/error.h"

namespace prt {
namespace {

std::string describe(const ParamSpec& s) {
  std::string range;
  if (s.min || s.max)
    range = fmt::format(" in [{}, {}]", s.min ? fmt::format("{}", *s.min) : "-inf",
                        s.max ? fmt::format("{}", *s.max) : "inf");
  if (!s.choices.empty()) {
    range = " one of {";
    for (std::size_t i = 0; i < s.choices.size(); ++i) range += (i ? ", " : "") + s.choices[i];
    range += "}";
  }
  return fmt::format("  {} ({}{}, default {}): {}", s.key, to_string(s.type), range,
                     s.default_value, s.doc);
}

std::string list_specs(std::span<const ParamSpec> specs) {
  std::string out;
  for (const auto& s : specs) out += "\n" + describe(s);
  for (const auto& s : shared_param_specs()) out += "\n" + describe(s);
  return out;
}

ParamSet::Value parse_value(const std::string& owner, const ParamSpec& spec,
                            const std::string& text) {
  auto fail = [&](std::string_view why) -> ParamSet::Value {
    throw ParameterError(
        fmt::format("{}: parameter {}={}: {}\n  {}", owner, spec.key, text, why, describe(spec)));
  };
  switch (spec.type) {
    case ParamType::kInt: {
      std::int64_t v = 0;
      auto [p, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
      if (ec != std::errc() || p != text.data() + text.size()) return fail("not an integer");
      if ((spec.min && static_cast<double>(v) < *spec.min) ||
          (spec.max && static_cast<double>(v) > *spec.max))
        return fail("out of range");
      return v;
    }
    case ParamType::kReal: {
      double v = 0;
      auto [p, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
      if (ec != std::errc() || p != text.data() + text.size() || !std::isfinite(v))
        return fail("not a number");
      if ((spec.min && v < *spec.min) || (spec.max && v > *spec.max)) return fail("out of range");
      return v;
    }
    case ParamType::kBool:
      if (text == "true" || text == "1" || text == "on" || text == "yes") return true;
      if (text == "false" || text == "0" || text == "off" || text == "no") return false;
      return fail("not a boolean (true/false)");
    case ParamType::kString:
    case ParamType::kEnum:
      if ((!spec.choices.empty() || spec.type == ParamType::kEnum) &&
          std::find(spec.choices.begin(), spec.choices.end(), text) == spec.choices.end())
        return fail("not one of the allowed values");
      return text;
  }
  return fail("unknown type");
}

std::string format_value(const ParamSet::Value& v) {
  return std::visit(
      [](const auto& x) -> std::string {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, bool>)
          return x ? "true" : "false";
        else if constexpr (std::is_same_v<T, std::string>)
          return x;
        else
          return fmt::format("{}", x);
      },
      v);
}

}  // namespace

std::string_view to_string(ParamType t) {
  switch (t) {
    case ParamType::kInt:
      return "int";
    case ParamType::kReal:
      return "real";
    case ParamType::kBool:
      return "bool";
    case ParamType::kString:
      return "string";
    case ParamType::kEnum:
      return "enum";
  }
  return "?";
}

std::span<const ParamSpec> shared_param_specs() {
  static const std::vector<ParamSpec> specs = {
      {"seed",
       ParamType::kInt,
       "1",
       0.0,
       4294967295.0,
       {},
       "random seed of every randomised step (deterministic per seed)"},
  };
  return specs;
}

ParamSet::ParamSet(std::string owner, std::span<const ParamSpec> specs,
                   const std::map<std::string, std::string>& given, Shared shared)
    : owner_(std::move(owner)), given_(given) {
  std::vector<ParamSpec> all(specs.begin(), specs.end());
  if (shared == Shared::kInclude)
    for (const auto& s : shared_param_specs()) all.push_back(s);
  for (const auto& s : all) {
    PRT_CHECK(!types_.contains(s.key), "duplicate parameter '{}' in {}", s.key, owner_);
    PRT_CHECK(s.type != ParamType::kEnum || !s.choices.empty(),
              "enum parameter '{}' of {} lists no choices", s.key, owner_);
    types_[s.key] = s.type;
    values_[s.key] = parse_value(owner_ + " (default)", s, s.default_value);
  }
  for (const auto& [key, text] : given) {
    // Named capture: clang before 16 cannot capture a structured binding (the fuzz preset).
    auto it = std::find_if(all.begin(), all.end(),
                           [&name = key](const ParamSpec& s) { return s.key == name; });
    if (it == all.end())
      throw ParameterError(fmt::format("{}: unknown parameter '{}'. Valid parameters:{}", owner_,
                                       key, list_specs(specs)));
    values_[key] = parse_value(owner_, *it, text);
  }
}

const ParamSet::Value& ParamSet::get(const std::string& key, ParamType type) const {
  auto it = values_.find(key);
  PRT_CHECK(it != values_.end(), "{} reads undeclared parameter '{}'", owner_, key);
  PRT_CHECK(types_.at(key) == type, "{} reads parameter '{}' as {} but declared it {}", owner_, key,
            to_string(type), to_string(types_.at(key)));
  return it->second;
}

std::int64_t ParamSet::get_int(const std::string& key) const {
  return std::get<std::int64_t>(get(key, ParamType::kInt));
}
double ParamSet::get_real(const std::string& key) const {
  return std::get<double>(get(key, ParamType::kReal));
}
bool ParamSet::get_bool(const std::string& key) const {
  return std::get<bool>(get(key, ParamType::kBool));
}
const std::string& ParamSet::get_string(const std::string& key) const {
  const auto it = types_.find(key);
  if (it != types_.end() && it->second == ParamType::kEnum) return get_enum_name(key);
  return std::get<std::string>(get(key, ParamType::kString));
}

const std::string& ParamSet::get_enum_name(const std::string& key) const {
  return std::get<std::string>(get(key, ParamType::kEnum));
}

void ParamSet::enum_not_mapped(const std::string& key, const std::string& value) const {
  throw Error(
      fmt::format("{}: enum parameter '{}' has the value '{}', which its reader does not map",
                  owner_, key, value));
}

std::map<std::string, std::string> ParamSet::canonical() const {
  std::map<std::string, std::string> out;
  for (const auto& [k, v] : values_) out[k] = format_value(v);
  return out;
}

std::map<std::string, std::string> ParamSet::parse_assignments(std::span<const std::string> items,
                                                               std::string_view option) {
  std::map<std::string, std::string> out;
  for (const auto& item : items) {
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0)
      throw ParameterError(fmt::format("{} '{}': expected key=value", option, item));
    const std::string key = item.substr(0, eq);
    if (out.contains(key)) throw ParameterError(fmt::format("{}: '{}' given twice", option, key));
    out[key] = item.substr(eq + 1);
  }
  return out;
}

}  // namespace prt
