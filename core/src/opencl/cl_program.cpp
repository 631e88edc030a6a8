#include "prtlab/opencl/cl_program.h"

#include <algorithm>
#include <cctype>

#include "prtlab/opencl/cl_context.h"
#include "prtlab/opencl/cl_error.h"
#include "prtlab/opencl/cl_kernel_sources.h"
#include "prtlab/base/error.h"

namespace prt {
namespace {

bool is_identifier(std::string_view s) {
  if (s.empty() || std::isdigit(static_cast<unsigned char>(s[0]))) return false;
  return std::all_of(s.begin(), s.end(),
                     [](unsigned char c) { return std::isalnum(c) || c == '_'; });
}

}  // namespace

KernelDefines::KernelDefines(std::initializer_list<std::pair<std::string, std::string>> entries) {
  for (const auto& [name, value] : entries) set(name, value);
}

KernelDefines& KernelDefines::set(std::string_view name, std::string_view value) {
  if (!is_identifier(name))
    throw ParameterError(fmt::format("OpenCL define '{}' is not an identifier", name));
  if (value.find('\n') != std::string_view::npos)
    throw ParameterError(fmt::format("OpenCL define {}: the value must be one line", name));
  auto it = std::find_if(entries_.begin(), entries_.end(),
                         [&](const auto& e) { return e.first == name; });
  if (it != entries_.end()) {
    it->second = std::string(value);
  } else {
    entries_.emplace_back(std::string(name), std::string(value));
  }
  return *this;
}

KernelDefines& KernelDefines::set(std::string_view name, float value) {
  // '#' keeps the decimal point, so 1.0f is "1.00000000f", a valid literal.
  return set(name, std::string_view(fmt::format("{:#.9g}f", value)));
}

std::string KernelDefines::text() const {
  std::string out;
  for (const auto& [name, value] : entries_) out += fmt::format("#define {} {}\n", name, value);
  return out;
}

std::string assemble_program_source(std::string_view label, std::string_view source,
                                    const KernelDefines& defines) {
  std::string out;
  if (!defines.entries().empty()) out += "#line 1 \"defines\"\n" + defines.text();
  out += "#line 1 \"prelude.cl\"\n";
  out += kernel_source("prelude");
  out += fmt::format("\n#line 1 \"{}\"\n", label);
  out += source;
  out += '\n';
  return out;
}

cl::Program build_program(ClContext& context, std::string_view kernel_file,
                          const KernelDefines& defines, std::string_view options) {
  const std::string_view source = kernel_source(kernel_file);  // throws listing known files
  std::string label(kernel_file);
  if (!label.ends_with(".cl")) label += ".cl";
  return build_program_source(context, label, source, defines, options);
}

cl::Program build_program_source(ClContext& context, std::string_view label,
                                 std::string_view source, const KernelDefines& defines,
                                 std::string_view options) {
  if (label.find_first_of("\"\\\n") != std::string_view::npos)
    throw ParameterError(
        fmt::format("OpenCL program label '{}' may not contain quotes, "
                    "backslashes or newlines",
                    label));
  return context.programs().get(label, assemble_program_source(label, source, defines),
                                std::string(options));
}

cl::Kernel make_kernel(const cl::Program& program, std::string_view name) {
  try {
    return cl::Kernel(program, std::string(name).c_str());
  } catch (const cl::Error& e) {
    std::string known;
    try {
      known = program.getInfo<CL_PROGRAM_KERNEL_NAMES>();
    } catch (const cl::Error&) {
      known = "(unknown)";
    }
    std::replace(known.begin(), known.end(), ';', ' ');
    throw ClError(e.err(), fmt::format("OpenCL: no kernel '{}' in the program ({} returned {}); "
                                       "its kernels: {}",
                                       name, e.what(), cl_error_name(e.err()), known));
  }
}

}  // namespace prt
