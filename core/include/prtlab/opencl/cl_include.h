#pragma once
// The one place prtlab includes the Khronos C++ bindings. The macros below are also set as
// PUBLIC compile definitions of prtlab_core (core/CMakeLists.txt), so a file that includes
// <CL/opencl.hpp> directly sees the same configuration; they are repeated here for tools that
// parse a header on its own.
//
// OpenCL 1.2 is the target: it is what PoCL, NVIDIA, AMD and Intel all support, and kernels
// must run on PoCL's CPU device. Exceptions are on: a raw cl:: call that fails throws
// cl::Error (never a silently ignored status code); prtlab's own helpers translate it into a
// prt::ClError naming the device and the operation (cl_error.h).
#ifndef CL_HPP_TARGET_OPENCL_VERSION
#define CL_HPP_TARGET_OPENCL_VERSION 120
#endif
#ifndef CL_HPP_MINIMUM_OPENCL_VERSION
#define CL_HPP_MINIMUM_OPENCL_VERSION 120
#endif
#ifndef CL_TARGET_OPENCL_VERSION
#define CL_TARGET_OPENCL_VERSION 120
#endif
#ifndef CL_HPP_ENABLE_EXCEPTIONS
#define CL_HPP_ENABLE_EXCEPTIONS
#endif

#include <CL/opencl.hpp>
