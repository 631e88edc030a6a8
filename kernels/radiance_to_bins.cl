// Local radiance in the SH basis evaluated at the local bins (the C++ reference is
// prt::to_pixel_basis, transfer/radiance_to_bins.h): one work-item per (vertex, bin),
// out[v M + j] = sum_i B[j, i] c[v n + i], with B (M x n, row-major) the cell integrals of the
// SH basis. Packed RGB in and out (the layout of prt::LocalRadiance).
// Host defines: PRT_SH_COUNT (n), PRT_LOCAL_COUNT (M).
__kernel PRT_WG_ATTR void radiance_sh_to_bins(const uint vertices,
                                              __global const float* restrict b,
                                              __global const float* restrict sh,
                                              __global float* restrict out) {
  const uint id = get_global_id(0);
  PRT_GUARD(id, vertices * PRT_LOCAL_COUNT);
  const uint v = id / PRT_LOCAL_COUNT, j = id % PRT_LOCAL_COUNT;
  float4 acc = (float4)(0.0f);
  for (int i = 0; i < PRT_SH_COUNT; ++i)
    acc += b[j * PRT_SH_COUNT + i] * prt_load_rgb3(sh, v * PRT_SH_COUNT + i);
  prt_store_rgb3(out, id, acc);
}
