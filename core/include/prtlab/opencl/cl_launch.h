#pragma once
// Launching kernels: always with an explicit work-group size and a global size padded up to a
// multiple of it. Left to choose, PoCL picks a divisor of the global size, which is 1 for a
// prime size (DESIGN.md, "OpenCL on PoCL"). Kernels therefore receive the real size as an
// argument and ignore work-items past it (PRT_GUARD in kernels/prelude.cl). Every launch is
// named and recorded in the context's KernelTimer.
#include <array>
#include <cstddef>
#include <string_view>
#include <vector>

#include "prtlab/opencl/cl_error.h"
#include "prtlab/opencl/cl_include.h"

namespace prt {

class ClContext;

/// The work-group size prtlab launches with unless a kernel asks otherwise; kernels/prelude.cl
/// defines PRT_WG_SIZE to the same value.
inline constexpr std::size_t kDefaultWorkGroupSize = 64;

/// n rounded up to a multiple of `multiple` (> 0).
constexpr std::size_t round_up(std::size_t n, std::size_t multiple) {
  return (n + multiple - 1) / multiple * multiple;
}

/// A padded launch geometry of 1 or 2 dimensions.
struct LaunchRange {
  int dims = 1;
  std::array<std::size_t, 2> size{0, 1};    ///< the real problem size
  std::array<std::size_t, 2> local{1, 1};   ///< work-group size
  std::array<std::size_t, 2> global{0, 1};  ///< size rounded up to a multiple of local

  /// n work-items in groups of `work_group`.
  static LaunchRange linear(std::size_t n, std::size_t work_group = kDefaultWorkGroupSize);
  /// nx x ny work-items in groups of wx x wy.
  static LaunchRange grid(std::size_t nx, std::size_t ny, std::size_t wx, std::size_t wy);
  std::size_t groups() const { return global[0] / local[0] * (global[1] / local[1]); }
};

/// Sets kernel arguments 0, 1, ... in order (cl::Buffer, scalars, cl::Local(bytes)); a failure
/// names the kernel and the argument index.
template <typename... Args>
void set_args(cl::Kernel& kernel, const Args&... args);
/// The same from argument index `first` (arguments a kernel's caller appends after its own).
template <typename... Args>
void set_args_from(cl::Kernel& kernel, cl_uint first, const Args&... args);

/// Enqueues `kernel` over `range` on the context's queue, records it in ctx.timer() under
/// `name` (the kernel's function name if empty) and returns its event. Does not wait. A work-
/// group size the kernel cannot use and out-of-memory conditions are reported as ClError /
/// DeviceOutOfMemory naming the kernel and the device.
cl::Event launch(ClContext& ctx, std::string_view name, const cl::Kernel& kernel,
                 const LaunchRange& range, const std::vector<cl::Event>* wait_for = nullptr);

namespace detail {
[[noreturn]] void throw_set_arg_error(const cl::Kernel& kernel, std::size_t index,
                                      const cl::Error& e);
}  // namespace detail

template <typename... Args>
void set_args_from(cl::Kernel& kernel, cl_uint first, const Args&... args) {
  cl_uint index = first;
  auto set_one = [&](const auto& arg) {
    try {
      kernel.setArg(index, arg);
    } catch (const cl::Error& e) {
      detail::throw_set_arg_error(kernel, index, e);
    }
    ++index;
  };
  (set_one(args), ...);
}

template <typename... Args>
void set_args(cl::Kernel& kernel, const Args&... args) {
  set_args_from(kernel, 0, args...);
}

}  // namespace prt
