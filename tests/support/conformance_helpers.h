#pragma once
// Checks shared by the conformance suites of transfer backends and of materials.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "prtlab/compress/params.h"
#include "prtlab/compress/storage_report.h"

namespace prt::testing {

/// A name usable in test names and file names: every non-alphanumeric character becomes '_'.
inline std::string sanitize_name(std::string s) {
  for (char& ch : s)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return s;
}

/// Same components (name, bytes, layout) in the same order.
inline ::testing::AssertionResult same_storage(const StorageReport& a, const StorageReport& b) {
  if (a.components.size() != b.components.size())
    return ::testing::AssertionFailure()
           << a.components.size() << " vs " << b.components.size() << " components";
  for (std::size_t i = 0; i < a.components.size(); ++i) {
    const auto &x = a.components[i], &y = b.components[i];
    if (x.name != y.name || x.bytes != y.bytes || x.layout != y.layout)
      return ::testing::AssertionFailure()
             << "component " << i << ": " << x.name << " " << x.bytes << " B (" << x.layout
             << ") vs " << y.name << " " << y.bytes << " B (" << y.layout << ")";
  }
  return ::testing::AssertionSuccess();
}

/// A scratch file `<dir>/<stem>.prt`, removed at scope exit.
struct ScratchFile {
  std::filesystem::path path;
  ScratchFile(const std::filesystem::path& dir, const std::string& stem)
      : path(dir / (sanitize_name(stem) + ".prt")) {}
  ~ScratchFile() {
    std::error_code ec;
    std::filesystem::remove(path, ec);
  }
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;
};

/// Every combination of device options a suite checks: string and enum choices, both bools,
/// and the default and two ends of numeric ranges.
inline std::vector<std::map<std::string, std::string>> device_option_sets(
    std::span<const ParamSpec> specs) {
  std::vector<std::map<std::string, std::string>> sets{{}};
  for (const auto& spec : specs) {
    std::vector<std::string> values;
    switch (spec.type) {
      case prt::ParamType::kString:
      case prt::ParamType::kEnum:
        values = spec.choices;
        break;
      case prt::ParamType::kBool:
        values = {"false", "true"};
        break;
      case prt::ParamType::kInt:
        values.push_back(spec.default_value);
        if (spec.min) values.push_back(fmt::format("{}", static_cast<long long>(*spec.min)));
        if (spec.max) values.push_back(fmt::format("{}", static_cast<long long>(*spec.max)));
        break;
      case prt::ParamType::kReal:
        values.push_back(spec.default_value);
        if (spec.min) values.push_back(fmt::format("{}", *spec.min));
        if (spec.max) values.push_back(fmt::format("{}", *spec.max));
        break;
    }
    std::sort(values.begin(), values.end());
    values.erase(std::unique(values.begin(), values.end()), values.end());
    if (values.empty()) continue;
    std::vector<std::map<std::string, std::string>> next;
    for (const auto& s : sets)
      for (const auto& v : values) {
        auto p = s;
        p[spec.key] = v;
        next.push_back(std::move(p));
      }
    sets = std::move(next);
  }
  return sets;
}

}  // namespace prt::testing
