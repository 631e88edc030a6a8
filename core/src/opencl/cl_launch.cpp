#include "prtlab/opencl/cl_launch.h"

#include <fmt/format.h>

#include "prtlab/opencl/cl_context.h"

namespace prt {
namespace {

std::string function_name(const cl::Kernel& kernel) {
  try {
    std::string name = kernel.getInfo<CL_KERNEL_FUNCTION_NAME>();
    while (!name.empty() && name.back() == '\0') name.pop_back();
    return name;
  } catch (const cl::Error&) {
    return "(unknown kernel)";
  }
}

// Explains CL_INVALID_WORK_GROUP_SIZE, queried only after the failure so that a successful
// launch costs no extra driver calls.
std::string work_group_diagnosis(ClContext& ctx, const cl::Kernel& kernel, const LaunchRange& r) {
  std::string out = fmt::format("work-group {}x{} is not allowed", r.local[0], r.local[1]);
  try {
    const auto max = kernel.getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(ctx.device());
    const auto reqd = kernel.getWorkGroupInfo<CL_KERNEL_COMPILE_WORK_GROUP_SIZE>(ctx.device());
    out += fmt::format(" (the kernel allows at most {} work-items per group", max);
    if (reqd[0] != 0)
      out += fmt::format(
          " and requires exactly {}x{}x{}: it declares reqd_work_group_size, "
          "so build it with PRT_WG_SIZE equal to the launch size",
          reqd[0], reqd[1], reqd[2]);
    out += ")";
  } catch (const cl::Error&) {
  }
  return out;
}

}  // namespace

LaunchRange LaunchRange::linear(std::size_t n, std::size_t work_group) {
  PRT_CHECK(work_group > 0, "work-group size must be positive");
  LaunchRange r;
  r.dims = 1;
  r.size = {n, 1};
  r.local = {work_group, 1};
  r.global = {round_up(n, work_group), 1};
  return r;
}

LaunchRange LaunchRange::grid(std::size_t nx, std::size_t ny, std::size_t wx, std::size_t wy) {
  PRT_CHECK(wx > 0 && wy > 0, "work-group size must be positive");
  LaunchRange r;
  r.dims = 2;
  r.size = {nx, ny};
  r.local = {wx, wy};
  r.global = {round_up(nx, wx), round_up(ny, wy)};
  return r;
}

cl::Event launch(ClContext& ctx, std::string_view name, const cl::Kernel& kernel,
                 const LaunchRange& range, const std::vector<cl::Event>* wait_for) {
  const std::string label = name.empty() ? function_name(kernel) : std::string(name);
  cl::Event event;
  if (range.global[0] == 0 || range.global[1] == 0) {
    // Nothing to do; an empty NDRange is an error in OpenCL, so enqueue a marker instead and
    // still count the launch.
    try {
      ctx.queue().enqueueMarkerWithWaitList(wait_for, &event);
    } catch (const cl::Error& e) {
      throw_cl_error(e, ctx.info().device_name, fmt::format("kernel {} (empty launch)", label));
    }
    ctx.timer().record(label, event);
    return event;
  }
  const cl::NDRange global = range.dims == 1 ? cl::NDRange(range.global[0])
                                             : cl::NDRange(range.global[0], range.global[1]);
  const cl::NDRange local =
      range.dims == 1 ? cl::NDRange(range.local[0]) : cl::NDRange(range.local[0], range.local[1]);
  try {
    ctx.queue().enqueueNDRangeKernel(kernel, cl::NullRange, global, local, wait_for, &event);
  } catch (const cl::Error& e) {
    if (e.err() == CL_INVALID_WORK_GROUP_SIZE)
      throw ClError(e.err(), fmt::format("OpenCL device {}: cannot launch kernel {}: {}",
                                         ctx.info().device_name, label,
                                         work_group_diagnosis(ctx, kernel, range)));
    throw_cl_error(
        e, ctx.info().device_name,
        fmt::format("kernel {} over {}x{} work-items", label, range.global[0], range.global[1]));
  }
  ctx.timer().record(label, event);
  return event;
}

namespace detail {
void throw_set_arg_error(const cl::Kernel& kernel, std::size_t index, const cl::Error& e) {
  throw ClError(e.err(),
                fmt::format("OpenCL kernel {}: setting argument {} failed: {} returned {} "
                            "(wrong type or size for the kernel's parameter?)",
                            function_name(kernel), index, e.what(), cl_error_name(e.err())));
}
}  // namespace detail

}  // namespace prt
