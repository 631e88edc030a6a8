#pragma once
// OpenCL kernel sources compiled into the binary. Every .cl file is embedded at build time by
// cmake/EmbedKernels.cmake into the library that launches it: core's own kernels (kernels/*.cl)
// into prtlab_core, a backend's (compressors/<name>/<name>*.cl) into that backend's objects. The
// generated code registers each file under its name when its library is loaded, so a binary
// never looks for kernels on disk and adding a backend's kernel edits nothing outside its
// folder. Programs are built from them with build_program(context, "<name>") (cl_program.h).
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace prt {

/// The source of the embedded file <name>.cl ("selftest" or "selftest.cl"). Throws prt::Error
/// listing the known names when there is no such file, or when two libraries embedded
/// different files of that name.
std::string_view kernel_source(std::string_view name);

/// True when <name>.cl was embedded.
bool has_kernel_source(std::string_view name);

/// Names of every embedded kernel file, sorted, without ".cl".
std::vector<std::string> kernel_names();

/// Registers one embedded file; written by cmake/embed_kernels.cmake at namespace scope.
/// Unregisters it when its library is unloaded (a plugin that failed to load).
class KernelSourceRegistrar {
 public:
  KernelSourceRegistrar(std::string_view name, std::string_view source) noexcept;
  ~KernelSourceRegistrar();
  KernelSourceRegistrar(const KernelSourceRegistrar&) = delete;
  KernelSourceRegistrar& operator=(const KernelSourceRegistrar&) = delete;

 private:
  std::string_view name_, source_;
};

}  // namespace prt
