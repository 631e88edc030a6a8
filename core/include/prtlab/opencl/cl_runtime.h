#pragma once
// prtlab's OpenCL runtime in one include. Each part has its own header:
//   cl_include.h         the Khronos C++ bindings, configured (OpenCL 1.2, exceptions)
//   cl_error.h           ClError, DeviceOutOfMemory, ClBuildError, cl_call()
//   cl_device.h          DeviceInfo, device selection (--device, PRTLAB_DEVICE, strict mode)
//   cl_context.h         ClContext: context + profiling queue + timer + program cache
//   cl_kernel_sources.h  kernels/*.cl embedded at build time, kernel_source("name")
//   cl_program.h         build_program(): defines + prelude + source, build log on failure
//   cl_program_cache.h   in-process and on-disk program caches
//   cl_launch.h          padded launches with explicit work-group sizes, set_args()
//   cl_buffer.h          buffers with out-of-memory errors a user can act on
//   cl_timer.h           named launch timings and the summary table
// docs/opencl.md is the user's guide.
#include "prtlab/opencl/cl_buffer.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/opencl/cl_device.h"
#include "prtlab/opencl/cl_error.h"
#include "prtlab/opencl/cl_include.h"
#include "prtlab/opencl/cl_kernel_sources.h"
#include "prtlab/opencl/cl_launch.h"
#include "prtlab/opencl/cl_program.h"
#include "prtlab/opencl/cl_program_cache.h"
#include "prtlab/opencl/cl_timer.h"
