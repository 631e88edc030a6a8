// kernels/btf_lookup.cl's prt_view_samples16 (16 directions a call, float16 with selects for the
// scalar version's branches) against the scalar prt_view_samples and against the C++
// btf_view_samples (btf.h), as dense weights over the views: the same interpolation to float
// rounding, for directions everywhere on the sphere (below the horizon, on the pole, on the
// axes, not finite) and for several grid sides in one call.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "prtlab/btf/btf.h"
#include "prtlab/opencl/cl_buffer.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/opencl/cl_kernel_sources.h"
#include "prtlab/opencl/cl_launch.h"
#include "prtlab/opencl/cl_program.h"
#include "prtlab/opencl/cl_runtime.h"

namespace prt {
namespace {

constexpr const char* kKernels = R"CL(
__kernel void both(const uint n, __global const float4* dirs, __global const int* sides,
                   __global int4* scalar_views, __global float4* scalar_w,
                   __global int4* vector_views, __global float4* vector_w) {
  const uint k = get_global_id(0);
  if (k * 16 >= n) return;
  float x[16], y[16], z[16];
  int side[16];
  for (int i = 0; i < 16; ++i) {
    const uint s = k * 16 + i;
    x[i] = dirs[s].x; y[i] = dirs[s].y; z[i] = dirs[s].z; side[i] = sides[s];
    int v[4];
    float w[4];
    prt_view_samples(side[i], dirs[s].xyz, v, w);
    scalar_views[s] = (int4)(v[0], v[1], v[2], v[3]);
    scalar_w[s] = (float4)(w[0], w[1], w[2], w[3]);
  }
  int16 views[4];
  float16 weights[4];
  prt_view_samples16(vload16(0, side), vload16(0, x), vload16(0, y), vload16(0, z), views, weights);
  int v[4][16];
  float w[4][16];
  for (int j = 0; j < 4; ++j) { vstore16(views[j], 0, v[j]); vstore16(weights[j], 0, w[j]); }
  for (int i = 0; i < 16; ++i) {
    vector_views[k * 16 + i] = (int4)(v[0][i], v[1][i], v[2][i], v[3][i]);
    vector_w[k * 16 + i] = (float4)(w[0][i], w[1][i], w[2][i], w[3][i]);
  }
}
)CL";

std::vector<double> dense(int side, const cl_int4& v, const cl_float4& w) {
  std::vector<double> d(static_cast<std::size_t>(side) * side, 0.0);
  for (int k = 0; k < 4; ++k) d.at(static_cast<std::size_t>(v.s[k])) += w.s[k];
  return d;
}

std::vector<double> dense_cpp(int side, Vec3 e) {
  const BtfViewSamples s = btf_view_samples(side, e);
  std::vector<double> d(static_cast<std::size_t>(side) * side, 0.0);
  for (int k = 0; k < 4; ++k) d.at(static_cast<std::size_t>(s.view[k])) += s.weight[k];
  return d;
}

double l1(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) s += std::abs(a[i] - b[i]);
  return s;
}

TEST(ViewSamples16, MatchesTheScalarKernelAndTheCppLookup) {
  ClContext* ctx = default_context();
  if (ctx == nullptr) GTEST_SKIP() << "no OpenCL device (install pocl-opencl-icd)";
  std::vector<cl_float4> dirs;
  std::vector<cl_int> sides;
  const int side_cycle[] = {1, 2, 5, 12, 16};
  std::mt19937 rng(3);
  std::normal_distribution<float> g;
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<Vec3> special = {{0, 0, 1},  {0, 0, -1},  {1, 0, 0},          {0, 1, 0},
                                     {-1, 0, 0}, {0, -1, 0},  {1, 1, 0},          {1, -1, 0.2f},
                                     {0, 0, 0},  {inf, 0, 1}, {0.3f, 0.4f, -0.8f}};
  for (std::size_t i = 0; i < 16 * 256; ++i) {
    const Vec3 d = i < special.size() ? special[i] : Vec3(g(rng), g(rng), g(rng));
    dirs.push_back(cl_float4{{d.x, d.y, d.z, 0.0f}});
    sides.push_back(side_cycle[i % 5]);
  }
  const std::string source = std::string(kernel_source("btf_lookup")) +
                             "\n#line 1 \"view_samples16_test.cl\"\n" + kKernels;
  const cl::Program program = build_program_source(*ctx, "btf_lookup.cl", source);
  cl::Kernel k = make_kernel(program, "both");
  const std::size_t n = dirs.size();
  const cl::Buffer d = upload(*ctx, std::span<const cl_float4>(dirs), "directions");
  const cl::Buffer s = upload(*ctx, std::span<const cl_int>(sides), "sides");
  const cl::Buffer sv = make_buffer(*ctx, n * sizeof(cl_int4), CL_MEM_WRITE_ONLY, "scalar views");
  const cl::Buffer sw = make_buffer(*ctx, n * sizeof(cl_float4), CL_MEM_WRITE_ONLY, "scalar w");
  const cl::Buffer vv = make_buffer(*ctx, n * sizeof(cl_int4), CL_MEM_WRITE_ONLY, "vector views");
  const cl::Buffer vw = make_buffer(*ctx, n * sizeof(cl_float4), CL_MEM_WRITE_ONLY, "vector w");
  set_args(k, static_cast<cl_uint>(n), d, s, sv, sw, vv, vw);
  launch(*ctx, "both", k, LaunchRange::linear(n / 16, 64));
  std::vector<cl_int4> scalar_views(n), vector_views(n);
  std::vector<cl_float4> scalar_w(n), vector_w(n);
  read_buffer(*ctx, sv, scalar_views.data(), n * sizeof(cl_int4), "scalar views");
  read_buffer(*ctx, sw, scalar_w.data(), n * sizeof(cl_float4), "scalar w");
  read_buffer(*ctx, vv, vector_views.data(), n * sizeof(cl_int4), "vector views");
  read_buffer(*ctx, vw, vector_w.data(), n * sizeof(cl_float4), "vector w");
  double worst_scalar = 0, worst_cpp = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const int side = sides[i];
    const std::vector<double> vec = dense(side, vector_views[i], vector_w[i]);
    worst_scalar = std::max(worst_scalar, l1(vec, dense(side, scalar_views[i], scalar_w[i])));
    const Vec3 e(dirs[i].s[0], dirs[i].s[1], dirs[i].s[2]);
    worst_cpp = std::max(worst_cpp, l1(vec, dense_cpp(side, e)));
    ASSERT_LT(l1(vec, dense_cpp(side, e)), 1e-4) << "direction " << i << " side " << side;
  }
  // Float rounding only: the fractions are ratios of distances on the unit sphere.
  EXPECT_LT(worst_scalar, 1e-5);
  EXPECT_LT(worst_cpp, 1e-4);
}

}  // namespace
}  // namespace prt
