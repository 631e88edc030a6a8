#pragma once
// Device buffers with errors a user can act on. Allocation checks the device's largest single
// buffer first and turns CL_MEM_OBJECT_ALLOCATION_FAILURE / CL_OUT_OF_RESOURCES into
// "OpenCL device X: out of memory allocating N MB for <what>" (DeviceOutOfMemory). Drivers
// often allocate lazily, so the first write or launch can fail instead; the helpers here
// report those the same way.
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <span>
#include <string_view>
#include <type_traits>
#include <vector>

#include "prtlab/base/types.h"
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
/// Writes an RGB light to `buffer` as float4 (RGB + a zero pad), the layout every relight kernel
/// reads; `scratch` is the caller's staging vector, kept to avoid an allocation per light.
void upload_light(ClContext& ctx, const cl::Buffer& buffer, std::span<const Rgb> light,
                  std::vector<cl_float4>& scratch, std::string_view what);

/// The bytes the buffers hold (CL_MEM_SIZE), for DeviceRelighter::device_bytes(): counted from
/// what was allocated, not recomputed by hand.
std::uint64_t buffer_bytes(std::initializer_list<const cl::Buffer*> buffers);

template <typename T>
requires std::is_trivially_copyable_v<T> cl::Buffer upload(ClContext& ctx, std::span<const T> data,
                                                           std::string_view what,
                                                           cl_mem_flags flags = CL_MEM_READ_ONLY) {
  cl::Buffer buffer = make_buffer(ctx, data.size_bytes(), flags, what);
  if (!data.empty()) write_buffer(ctx, buffer, data.data(), data.size_bytes(), what);
  return buffer;
}

/// Blocking read of out.size() elements from the start of `buffer`.
/// Writes an RGB light to `buffer` as float4 (RGB + a zero pad), the layout every relight kernel
/// reads; `scratch` is the caller's staging vector, kept to avoid an allocation per light.
void upload_light(ClContext& ctx, const cl::Buffer& buffer, std::span<const Rgb> light,
                  std::vector<cl_float4>& scratch, std::string_view what);

/// The bytes the buffers hold (CL_MEM_SIZE), for DeviceRelighter::device_bytes(): counted from
/// what was allocated, not recomputed by hand.
std::uint64_t buffer_bytes(std::initializer_list<const cl::Buffer*> buffers);

template <typename T>
requires std::is_trivially_copyable_v<T>
void download(ClContext& ctx, const cl::Buffer& buffer, std::span<T> out, std::string_view what) {
  if (!out.empty()) read_buffer(ctx, buffer, out.data(), out.size_bytes(), what);
}

}  // namespace prt
