#include "prtlab/opencl/cl_kernel_sources.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>

#include "prtlab/base/error.h"

namespace prt {
namespace {

std::string_view strip_extension(std::string_view name) {
  constexpr std::string_view kExt = ".cl";
  if (name.size() > kExt.size() && name.substr(name.size() - kExt.size()) == kExt)
    name.remove_suffix(kExt.size());
  return name;
}

const detail::EmbeddedKernel* find(std::string_view name) {
  name = strip_extension(name);
  for (const auto& k : detail::embedded_kernels())
    if (k.name == name) return &k;
  return nullptr;
}

}  // namespace

std::string_view kernel_source(std::string_view name) {
  if (const auto* k = find(name)) return k->source;
  throw Error(
      fmt::format("no OpenCL kernel file '{}' is embedded in this binary (known: {}); a "
                  "backend's kernels go in kernels/<name>.cl and are embedded at build time",
                  name, fmt::join(kernel_names(), ", ")));
}

bool has_kernel_source(std::string_view name) {
  return find(name) != nullptr;
}

std::vector<std::string> kernel_names() {
  std::vector<std::string> names;
  for (const auto& k : detail::embedded_kernels()) names.emplace_back(k.name);
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace prt
