#pragma once
// Typed, documented backend parameters (libpressio / Mitsuba style).
//
// A backend declares its parameters as data (ParamSpec: key, type, default, range, doc). The
// user's values arrive as strings ("clusters=32") and are validated up front by ParamSet:
// an unknown key, a value of the wrong type or out of range is a ParameterError that lists
// the valid keys with their documentation. Keys shared by every backend are in
// shared_param_specs() ("seed", ...).
#include <cstdint>
#include <initializer_list>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

namespace prt {

/// kEnum: one of `choices` (required, default among them), read with get_enum() or
/// get_string(); kString: any text, or one of `choices` when given.
enum class ParamType { kInt, kReal, kBool, kString, kEnum };
std::string_view to_string(ParamType t);

struct ParamSpec {
  std::string key;
  ParamType type = ParamType::kReal;
  std::string default_value;         ///< as the user would write it
  std::optional<double> min;         ///< inclusive, for kInt / kReal
  std::optional<double> max;         ///< inclusive, for kInt / kReal
  std::vector<std::string> choices;  ///< for kString: the allowed values (empty: any)
  std::string doc;                   ///< one sentence, with units
};

/// Parameters every backend accepts.
std::span<const ParamSpec> shared_param_specs();

class ParamSet {
 public:
  using Value = std::variant<std::int64_t, double, bool, std::string>;

  ParamSet() = default;
  /// Whether the shared specs (seed, ...) are added: yes for compression parameters, no for
  /// device options (CompressorEntry::device_params).
  enum class Shared { kInclude, kExclude };
  /// Validates `given` against `specs` (plus the shared specs unless excluded). `owner` names
  /// the backend in messages.
  ParamSet(std::string owner, std::span<const ParamSpec> specs,
           const std::map<std::string, std::string>& given, Shared shared = Shared::kInclude);

  std::int64_t get_int(const std::string& key) const;
  double get_real(const std::string& key) const;
  bool get_bool(const std::string& key) const;
  /// kString or kEnum.
  const std::string& get_string(const std::string& key) const;
  /// A kEnum value mapped through `names` (every choice of the spec must be listed: a missing
  /// one is an internal error naming it).
  template <typename E>
  E get_enum(const std::string& key,
             std::initializer_list<std::pair<std::string_view, E>> names) const {
    const std::string& value = get_enum_name(key);
    for (const auto& [name, e] : names)
      if (name == value) return e;
    enum_not_mapped(key, value);
  }
  bool was_given(const std::string& key) const { return given_.contains(key); }
  /// Every value (given or default) as "key=value" strings, sorted: used in cache keys and reports.
  std::map<std::string, std::string> canonical() const;

  /// Parse "k=v" strings (from --param, or the option named `option`) into a map; malformed
  /// entries are a ParameterError naming the option and the entry.
  static std::map<std::string, std::string> parse_assignments(std::span<const std::string> items,
                                                              std::string_view option = "--param");

 private:
  const Value& get(const std::string& key, ParamType type) const;
  const std::string& get_enum_name(const std::string& key) const;
  [[noreturn]] void enum_not_mapped(const std::string& key, const std::string& value) const;
  std::string owner_;
  std::map<std::string, Value> values_;
  std::map<std::string, ParamType> types_;
  std::map<std::string, std::string> given_;
};

}  // namespace prt
