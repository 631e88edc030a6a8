#pragma once
// Building OpenCL programs (the OpenMM pattern): one function takes a kernel file, prepends the
// caller's defines and kernels/prelude.cl, builds for the context's device through the
// context's ProgramCache (cl_program_cache.h), and on failure throws a ClBuildError carrying
// the build log, the device name and the options. #line markers keep compiler messages
// pointing at the original file and line ("selftest.cl:12:3: error: ...").
#include <fmt/format.h>

#include <concepts>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "prtlab/opencl/cl_include.h"

namespace prt {

class ClContext;

/// Preprocessor definitions for a program, emitted as "#define NAME VALUE" lines before the
/// prelude (so they override its defaults, e.g. PRT_WG_SIZE). Setting a name again replaces
/// its value; the order of first definition is kept, so the source (and the cache key) is
/// deterministic.
class KernelDefines {
 public:
  KernelDefines() = default;
  KernelDefines(std::initializer_list<std::pair<std::string, std::string>> entries);

  KernelDefines& set(std::string_view name, std::string_view value = "1");
  KernelDefines& set(std::string_view name, const char* value) {
    return set(name, std::string_view(value));
  }
  KernelDefines& set(std::string_view name, const std::string& value) {
    return set(name, std::string_view(value));
  }
  template <std::integral T>
  requires(!std::same_as<T, bool>) KernelDefines& set(std::string_view name, T value) {
    return set(name, std::string_view(fmt::format("{}", value)));
  }
  /// As an OpenCL float literal with 9 significant digits ("0.100000001f").
  KernelDefines& set(std::string_view name, float value);

  const std::vector<std::pair<std::string, std::string>>& entries() const { return entries_; }
  /// The "#define" lines.
  std::string text() const;

 private:
  std::vector<std::pair<std::string, std::string>> entries_;
};

/// The text actually compiled: defines, then kernels/prelude.cl, then `source`, each part
/// introduced by a #line marker naming its file.
std::string assemble_program_source(std::string_view label, std::string_view source,
                                    const KernelDefines& defines);

/// Builds kernels/<kernel_file>.cl (embedded, see cl_kernel_sources.h) for `context`'s device;
/// cached in the process and on disk. `options` are clBuildProgram options
/// ("-cl-mad-enable"); both they and the defines are part of the cache key.
cl::Program build_program(ClContext& context, std::string_view kernel_file,
                          const KernelDefines& defines = {}, std::string_view options = {});

/// The same for source text that is not an embedded kernel file (plugins, tests); `label`
/// names it in messages and #line markers.
cl::Program build_program_source(ClContext& context, std::string_view label,
                                 std::string_view source, const KernelDefines& defines = {},
                                 std::string_view options = {});

/// A kernel of a built program; throws ClError naming the program's kernels when there is no
/// kernel of that name.
cl::Kernel make_kernel(const cl::Program& program, std::string_view name);

}  // namespace prt
