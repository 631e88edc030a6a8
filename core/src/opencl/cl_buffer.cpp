#include "prtlab/opencl/cl_buffer.h"

#include <fmt/format.h>

#include <algorithm>

#include "prtlab/opencl/cl_context.h"
#include "prtlab/opencl/cl_error.h"

namespace prt {

cl::Buffer make_buffer(ClContext& ctx, std::size_t bytes, cl_mem_flags flags,
                       std::string_view what) {
  const DeviceInfo& info = ctx.info();
  if (info.max_alloc_bytes > 0 && bytes > info.max_alloc_bytes)
    throw DeviceOutOfMemory(
        CL_INVALID_BUFFER_SIZE,
        fmt::format("OpenCL device {}: out of memory allocating {:.1f} MB for {} (the device's "
                    "largest single buffer is {:.1f} MB, {:.1f} MB in all)",
                    info.device_name, static_cast<double>(bytes) / 1e6, what,
                    static_cast<double>(info.max_alloc_bytes) / 1e6,
                    static_cast<double>(info.global_mem_bytes) / 1e6));
  try {
    return cl::Buffer(ctx.context(), flags, std::max<std::size_t>(bytes, 16));
  } catch (const cl::Error& e) {
    throw_cl_error(e, info.device_name, what, bytes);
  }
}

void write_buffer(ClContext& ctx, const cl::Buffer& buffer, const void* data, std::size_t bytes,
                  std::string_view what, std::size_t offset) {
  try {
    ctx.queue().enqueueWriteBuffer(buffer, CL_TRUE, offset, bytes, data);
  } catch (const cl::Error& e) {
    throw_cl_error(e, ctx.info().device_name, fmt::format("upload of {}", what), bytes);
  }
}

void read_buffer(ClContext& ctx, const cl::Buffer& buffer, void* data, std::size_t bytes,
                 std::string_view what, std::size_t offset) {
  try {
    ctx.queue().enqueueReadBuffer(buffer, CL_TRUE, offset, bytes, data);
  } catch (const cl::Error& e) {
    throw_cl_error(e, ctx.info().device_name, fmt::format("read-back of {}", what));
  }
}

void upload_light(ClContext& ctx, const cl::Buffer& buffer, std::span<const Rgb> light,
                  std::vector<cl_float4>& scratch, std::string_view what) {
  scratch.resize(light.size());
  for (std::size_t k = 0; k < light.size(); ++k)
    scratch[k] = cl_float4{{light[k].x, light[k].y, light[k].z, 0.f}};
  if (!scratch.empty())
    write_buffer(ctx, buffer, scratch.data(), scratch.size() * sizeof(cl_float4), what);
}

std::uint64_t buffer_bytes(std::initializer_list<const cl::Buffer*> buffers) {
  std::uint64_t bytes = 0;
  for (const cl::Buffer* b : buffers)
    if (b && (*b)() != nullptr) bytes += b->getInfo<CL_MEM_SIZE>();
  return bytes;
}

}  // namespace prt
