// Self-test kernels for tests/core/cl_runtime_test.cpp: exercise the prelude's float4 helpers,
// global-size padding (a guard) and a work-group reduction (local memory + barriers).

// y[i] = a * x[i] + y[i] on RGB+pad float4 values, i < n.
__kernel void saxpy4(const uint n, const float a, __global const float4* x, __global float4* y) {
  const size_t i = get_global_id(0);
  PRT_GUARD(i, n);
  y[i] = a * x[i] + y[i];
}

// partial[g] = sum of x[i] over work-group g, i < n. Work-items past n contribute 0 but stay
// in the loop, so every barrier is reached by the whole group. PRT_WG_SIZE: a power of two.
__kernel PRT_WG_ATTR void reduce_sum(const uint n, __global const float* x, __global float* partial) {
  __local float scratch[PRT_WG_SIZE];
  const size_t i = get_global_id(0);
  const size_t lid = get_local_id(0);
  scratch[lid] = i < n ? x[i] : 0.0f;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (size_t stride = PRT_WG_SIZE / 2; stride > 0; stride /= 2) {
    if (lid < stride) scratch[lid] += scratch[lid + stride];
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  if (lid == 0) partial[get_group_id(0)] = scratch[0];
}
