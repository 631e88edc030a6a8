#include "prtlab/opencl/cl_error.h"

#include <fmt/format.h>

namespace prt {

std::string cl_error_name(int code) {
  switch (code) {
#define PRT_CL_CODE(c) \
  case c:              \
    return #c;
    PRT_CL_CODE(CL_SUCCESS)
    PRT_CL_CODE(CL_DEVICE_NOT_FOUND)
    PRT_CL_CODE(CL_DEVICE_NOT_AVAILABLE)
    PRT_CL_CODE(CL_COMPILER_NOT_AVAILABLE)
    PRT_CL_CODE(CL_MEM_OBJECT_ALLOCATION_FAILURE)
    PRT_CL_CODE(CL_OUT_OF_RESOURCES)
    PRT_CL_CODE(CL_OUT_OF_HOST_MEMORY)
    PRT_CL_CODE(CL_PROFILING_INFO_NOT_AVAILABLE)
    PRT_CL_CODE(CL_MEM_COPY_OVERLAP)
    PRT_CL_CODE(CL_IMAGE_FORMAT_MISMATCH)
    PRT_CL_CODE(CL_IMAGE_FORMAT_NOT_SUPPORTED)
    PRT_CL_CODE(CL_BUILD_PROGRAM_FAILURE)
    PRT_CL_CODE(CL_MAP_FAILURE)
    PRT_CL_CODE(CL_MISALIGNED_SUB_BUFFER_OFFSET)
    PRT_CL_CODE(CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST)
    PRT_CL_CODE(CL_COMPILE_PROGRAM_FAILURE)
    PRT_CL_CODE(CL_LINKER_NOT_AVAILABLE)
    PRT_CL_CODE(CL_LINK_PROGRAM_FAILURE)
    PRT_CL_CODE(CL_DEVICE_PARTITION_FAILED)
    PRT_CL_CODE(CL_KERNEL_ARG_INFO_NOT_AVAILABLE)
    PRT_CL_CODE(CL_INVALID_VALUE)
    PRT_CL_CODE(CL_INVALID_DEVICE_TYPE)
    PRT_CL_CODE(CL_INVALID_PLATFORM)
    PRT_CL_CODE(CL_INVALID_DEVICE)
    PRT_CL_CODE(CL_INVALID_CONTEXT)
    PRT_CL_CODE(CL_INVALID_QUEUE_PROPERTIES)
    PRT_CL_CODE(CL_INVALID_COMMAND_QUEUE)
    PRT_CL_CODE(CL_INVALID_HOST_PTR)
    PRT_CL_CODE(CL_INVALID_MEM_OBJECT)
    PRT_CL_CODE(CL_INVALID_IMAGE_FORMAT_DESCRIPTOR)
    PRT_CL_CODE(CL_INVALID_IMAGE_SIZE)
    PRT_CL_CODE(CL_INVALID_SAMPLER)
    PRT_CL_CODE(CL_INVALID_BINARY)
    PRT_CL_CODE(CL_INVALID_BUILD_OPTIONS)
    PRT_CL_CODE(CL_INVALID_PROGRAM)
    PRT_CL_CODE(CL_INVALID_PROGRAM_EXECUTABLE)
    PRT_CL_CODE(CL_INVALID_KERNEL_NAME)
    PRT_CL_CODE(CL_INVALID_KERNEL_DEFINITION)
    PRT_CL_CODE(CL_INVALID_KERNEL)
    PRT_CL_CODE(CL_INVALID_ARG_INDEX)
    PRT_CL_CODE(CL_INVALID_ARG_VALUE)
    PRT_CL_CODE(CL_INVALID_ARG_SIZE)
    PRT_CL_CODE(CL_INVALID_KERNEL_ARGS)
    PRT_CL_CODE(CL_INVALID_WORK_DIMENSION)
    PRT_CL_CODE(CL_INVALID_WORK_GROUP_SIZE)
    PRT_CL_CODE(CL_INVALID_WORK_ITEM_SIZE)
    PRT_CL_CODE(CL_INVALID_GLOBAL_OFFSET)
    PRT_CL_CODE(CL_INVALID_EVENT_WAIT_LIST)
    PRT_CL_CODE(CL_INVALID_EVENT)
    PRT_CL_CODE(CL_INVALID_OPERATION)
    PRT_CL_CODE(CL_INVALID_GL_OBJECT)
    PRT_CL_CODE(CL_INVALID_BUFFER_SIZE)
    PRT_CL_CODE(CL_INVALID_MIP_LEVEL)
    PRT_CL_CODE(CL_INVALID_GLOBAL_WORK_SIZE)
    PRT_CL_CODE(CL_INVALID_PROPERTY)
    PRT_CL_CODE(CL_INVALID_IMAGE_DESCRIPTOR)
    PRT_CL_CODE(CL_INVALID_COMPILER_OPTIONS)
    PRT_CL_CODE(CL_INVALID_LINKER_OPTIONS)
    PRT_CL_CODE(CL_INVALID_DEVICE_PARTITION_COUNT)
#undef PRT_CL_CODE
    case -1001:
      return "CL_PLATFORM_NOT_FOUND_KHR";
    default:
      return fmt::format("CL error {}", code);
  }
}

bool is_out_of_memory_code(int code) {
  return code == CL_MEM_OBJECT_ALLOCATION_FAILURE || code == CL_OUT_OF_RESOURCES ||
         code == CL_OUT_OF_HOST_MEMORY;
}

std::string out_of_memory_message(std::string_view device_name, std::uint64_t bytes,
                                  std::string_view what, int code) {
  if (bytes > 0)
    return fmt::format("OpenCL device {}: out of memory allocating {:.1f} MB for {} ({})",
                       device_name, static_cast<double>(bytes) / 1e6, what, cl_error_name(code));
  return fmt::format(
      "OpenCL device {}: out of memory during {} ({}; the driver allocates "
      "buffers lazily, so this is usually the total of the buffers it uses)",
      device_name, what, cl_error_name(code));
}

void throw_cl_error(int code, std::string_view call, std::string_view device_name,
                    std::string_view what, std::uint64_t bytes) {
  if (is_out_of_memory_code(code))
    throw DeviceOutOfMemory(code, out_of_memory_message(device_name, bytes, what, code));
  throw ClError(code, fmt::format("OpenCL device {}: {} failed: {} returned {}", device_name, what,
                                  call, cl_error_name(code)));
}

}  // namespace prt
