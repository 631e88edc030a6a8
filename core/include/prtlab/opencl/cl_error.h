#pragma once
// OpenCL failures as prtlab exceptions. Raw cl:: calls throw cl::Error (exceptions are enabled
// in cl_include.h); prtlab's helpers catch it and throw a ClError whose message names the
// device, the operation and the error code, so a user sees one sentence instead of "-5".
// Running out of device memory gets its own type and message, because it is the failure a
// user can fix (smaller scene, other device) and the one drivers report in the least obvious
// way (often at the first launch, not at the allocation).
#include <cstdint>
#include <string>
#include <string_view>

#include "prtlab/opencl/cl_include.h"
#include "prtlab/base/error.h"

namespace prt {

/// Symbolic name of an OpenCL status code ("CL_OUT_OF_RESOURCES"); "CL error <n>" if unknown.
std::string cl_error_name(int code);

/// True for the codes drivers use when device or host memory runs out
/// (CL_MEM_OBJECT_ALLOCATION_FAILURE, CL_OUT_OF_RESOURCES, CL_OUT_OF_HOST_MEMORY).
bool is_out_of_memory_code(int code);

/// An OpenCL call failed. code() is the OpenCL status (negative).
class ClError : public Error {
 public:
  ClError(int code, const std::string& message) : Error(message), code_(code) {}
  int code() const { return code_; }

 private:
  int code_;
};

/// "OpenCL device X: out of memory allocating N MB for <what> (CL_...)".
class DeviceOutOfMemory : public ClError {
 public:
  using ClError::ClError;
};

/// A program did not compile. what() holds the program's label, the device, the build
/// options and the complete build log; build_log() is the log alone.
class ClBuildError : public ClError {
 public:
  ClBuildError(int code, const std::string& message, std::string log)
      : ClError(code, message), log_(std::move(log)) {}
  const std::string& build_log() const { return log_; }

 private:
  std::string log_;
};

/// The message used for out-of-memory failures; `bytes` = 0 when the size is not known
/// (a launch or a copy that made the driver allocate lazily).
std::string out_of_memory_message(std::string_view device_name, std::uint64_t bytes,
                                  std::string_view what, int code);

/// Throws the prtlab exception for a failed OpenCL call: DeviceOutOfMemory for the memory
/// codes, ClError otherwise. `what` says what prtlab was doing ("upload of bicluster ids",
/// "kernel relight_rows"); `bytes` is the allocation size when there was one.
[[noreturn]] void throw_cl_error(int code, std::string_view call, std::string_view device_name,
                                 std::string_view what, std::uint64_t bytes = 0);
[[noreturn]] inline void throw_cl_error(const cl::Error& e, std::string_view device_name,
                                        std::string_view what, std::uint64_t bytes = 0) {
  throw_cl_error(e.err(), e.what(), device_name, what, bytes);
}

/// Runs f() and turns a cl::Error escaping it into a prtlab exception (see throw_cl_error).
/// For backend code that makes raw cl:: calls:
///   cl_call(ctx.info().device_name, "readback of relit radiance", [&] {
///   queue.enqueueReadBuffer(...); });
template <typename F>
decltype(auto) cl_call(std::string_view device_name, std::string_view what, F&& f) {
  try {
    return f();
  } catch (const cl::Error& e) {
    throw_cl_error(e, device_name, what);
  }
}

}  // namespace prt
