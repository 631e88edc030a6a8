#pragma once
// Device buffers with errors a user can act on. Allocation checks the device's largest single
// buffer first and turns CL_MEM_OBJECT_ALLOCATION_FAILURE / CL_OUT_OF_RESOURCES into
// "OpenCL device X: out of memory allocating N MB for <what>" (DeviceOutOfMemory). Drivers
// often allocate lazily, so the first write or launch can fail instead; the helpers here
// report those the same way.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <type_traits>

#include "prtlab/opencl/cl_include.h"

namespace prt {

class ClContext;

/// A buffer of `bytes` bytes. An empty buffer (bytes = 0, which OpenCL forbids) is allocated
/// with 16 bytes, so a kernel can always be given a valid argument for an empty array.
cl::Buffer make_buffer(ClContext& ctx, std::size_t bytes, cl_mem_flags flags,
                       std::string_view what);

/// Blocking copy host -> device of `bytes` bytes at byte `offset`.
void write_buffer(ClContext& ctx, const cl::Buffer& buffer, const void* data, std::size_t bytes,
                  std::string_view what, std::size_t offset = 0);
/// Blocking copy device -> host.
void read_buffer(ClContext& ctx, const cl::Buffer& buffer, void* data, std::size_t bytes,
                 std::string_view what, std::size_t offset = 0);

/// A new buffer holding `data` (blocking upload).
template <typename T>
requires std::is_trivially_copyable_v<T> cl::Buffer upload(ClContext& ctx, std::span<const T> data,
                                                           std::string_view what,
                                                           cl_mem_flags flags = CL_MEM_READ_ONLY) {
  cl::Buffer buffer = make_buffer(ctx, data.size_bytes(), flags, what);
  if (!data.empty()) write_buffer(ctx, buffer, data.data(), data.size_bytes(), what);
  return buffer;
}

/// Blocking read of out.size() elements from the start of `buffer`.
template <typename T>
requires std::is_trivially_copyable_v<T>
void download(ClContext& ctx, const cl::Buffer& buffer, std::span<T> out, std::string_view what) {
  if (!out.empty()) read_buffer(ctx, buffer, out.data(), out.size_bytes(), what);
}

}  // namespace prt
