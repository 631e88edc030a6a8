// Prepended to every program by prt::build_program (core/include/prtlab/opencl/cl_program.h), after the
// caller's defines, so anything here can be overridden with a define. Keep it small: it is
// compiled with every kernel file.

// Work-group size the host launches with (prt::kDefaultWorkGroupSize unless the host defines
// PRT_WG_SIZE). Kernels that size local arrays by it should also declare PRT_WG_ATTR, so a
// launch with another size fails loudly instead of overrunning the array.
#ifndef PRT_WG_SIZE
#define PRT_WG_SIZE 64
#endif
#define PRT_WG_ATTR __attribute__((reqd_work_group_size(PRT_WG_SIZE, 1, 1)))

// Double precision is optional in OpenCL 1.2; kernels that want it test PRT_HAS_FP64.
#if defined(cl_khr_fp64)
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#define PRT_HAS_FP64 1
#else
#define PRT_HAS_FP64 0
#endif

// RGB radiance travels as float4 (r, g, b, pad): aligned 16-byte loads, and PoCL vectorises
// float4 arithmetic where it does not vectorise three scalar channels (DESIGN.md).
inline float4 prt_rgb(float r, float g, float b) { return (float4)(r, g, b, 0.0f); }
inline float4 prt_load_rgb3(__global const float* rgb, size_t i) {
  return (float4)(vload3(i, rgb), 0.0f);
}
inline void prt_store_rgb3(__global float* rgb, size_t i, float4 v) { vstore3(v.xyz, i, rgb); }
inline float prt_sum3(float4 v) { return v.x + v.y + v.z; }
inline float prt_luminance(float4 v) { return 0.2126f * v.x + 0.7152f * v.y + 0.0722f * v.z; }

// Launches pad the global size up to a multiple of the work-group size: work-items past the
// real size must not write. Use PRT_GUARD(i, n) at the top of kernels without barriers; a
// kernel with barriers must keep every work-item alive until its last barrier (a divergent
// barrier is undefined behaviour and a known PoCL miscompile) and only mask the work.
#define PRT_GUARD(i, n) \
  if ((i) >= (n)) return
