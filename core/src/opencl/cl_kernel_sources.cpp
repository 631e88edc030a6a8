#include "prtlab/opencl/cl_kernel_sources.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <map>
#include <mutex>
#include <set>

#include "prtlab/base/error.h"

namespace prt {
namespace {

std::string_view strip_extension(std::string_view name) {
  constexpr std::string_view kExt = ".cl";
  if (name.size() > kExt.size() && name.substr(name.size() - kExt.size()) == kExt)
    name.remove_suffix(kExt.size());
  return name;
}

struct KernelTable {
  std::mutex mutex;
  std::map<std::string, std::string_view, std::less<>> sources;
  std::set<std::string, std::less<>> clashes;  // names embedded twice with different text
};

KernelTable& table() {
  static KernelTable t;
  return t;
}

}  // namespace

KernelSourceRegistrar::KernelSourceRegistrar(std::string_view name,
                                             std::string_view source) noexcept
    : name_(name), source_(source) {
  auto& t = table();
  const std::lock_guard lock(t.mutex);
  const auto [it, inserted] = t.sources.try_emplace(std::string(name), source);
  if (!inserted && it->second != source) t.clashes.emplace(name);
}

KernelSourceRegistrar::~KernelSourceRegistrar() {
  auto& t = table();
  const std::lock_guard lock(t.mutex);
  if (const auto it = t.sources.find(name_);
      it != t.sources.end() && it->second.data() == source_.data())
    t.sources.erase(it);
}

std::string_view kernel_source(std::string_view name) {
  name = strip_extension(name);
  auto& t = table();
  {
    const std::lock_guard lock(t.mutex);
    if (t.clashes.contains(name))
      throw Error(fmt::format(
          "two different OpenCL kernel files named '{}.cl' are embedded in this program (a "
          "plugin's and a built-in one?); kernel files are named after their backend",
          name));
    if (const auto it = t.sources.find(name); it != t.sources.end()) return it->second;
  }
  throw Error(fmt::format(
      "no OpenCL kernel file '{}' is embedded in this binary (known: {}); a backend's kernels "
      "go in compressors/<name>/<name>*.cl and are embedded at build time",
      name, fmt::join(kernel_names(), ", ")));
}

bool has_kernel_source(std::string_view name) {
  auto& t = table();
  const std::lock_guard lock(t.mutex);
  return t.sources.contains(strip_extension(name));
}

std::vector<std::string> kernel_names() {
  auto& t = table();
  const std::lock_guard lock(t.mutex);
  std::vector<std::string> names;
  for (const auto& [name, source] : t.sources) names.push_back(name);
  return names;
}

}  // namespace prt
