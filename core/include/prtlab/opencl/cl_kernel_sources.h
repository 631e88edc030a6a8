#pragma once
// OpenCL kernel sources compiled into the binary. Every kernels/<name>.cl of the source tree is
// embedded at build time by cmake/EmbedKernels.cmake (regenerated when a .cl file changes or
// one is added or removed), so a binary never depends on finding its kernels on disk. A
// backend adds kernels/<backend>.cl and nothing else; it then builds it with
// build_program(context, "<backend>") (cl_program.h).
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace prt {

/// The source of kernels/<name>.cl ("selftest" or "selftest.cl"). Throws prt::Error listing
/// the known names when there is no such kernel file.
std::string_view kernel_source(std::string_view name);

/// True when kernels/<name>.cl was embedded.
bool has_kernel_source(std::string_view name);

/// Names of every embedded kernel file, sorted, without ".cl".
std::vector<std::string> kernel_names();

namespace detail {
/// One embedded file; the table is written by cmake/embed_kernels.cmake.
struct EmbeddedKernel {
  std::string_view name;
  std::string_view source;
};
std::span<const EmbeddedKernel> embedded_kernels();
}  // namespace detail

}  // namespace prt
