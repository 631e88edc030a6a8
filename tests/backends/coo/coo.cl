// Test-only backend `coo`: one work-item per row sums its run [starts[row], starts[row + 1]) of
// (column, value) pairs against the float4 light; output packed RGB (prt::LocalRadiance).
__kernel PRT_WG_ATTR void coo_relight(const uint rows, __global const uint* restrict starts,
                                      __global const uint* restrict columns,
                                      __global const float* restrict values,
                                      __global const float4* restrict light,
                                      __global float* restrict out) {
  const uint row = get_global_id(0);
  PRT_GUARD(row, rows);
  float4 acc = (float4)(0.0f);
  for (uint i = starts[row]; i < starts[row + 1]; ++i) acc += values[i] * light[columns[i]];
  prt_store_rgb3(out, row, acc);
}
