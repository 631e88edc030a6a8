// BTF shading speed on the bunny (scenes/bunny.toml, stucco BTF 32 x 32 texels x 144 views x
// M = 64, front view at 640 x 480), against the read bandwidth of the same OpenCL device
// measured in the same process:
//
//   shading/single_pass/<filter>   btf_shade_single: view + texel interpolation and the dot
//                                  product in one kernel (ShadingOptions::cache_view_vectors off)
//   shading/view_cache/<filter>    btf_view_cache: b(u, e) of every hit pixel, written to the
//                                  device (what a view change adds)
//   shading/cached_shade/<filter>  btf_shade_cached: the dot products with the cached b(u, e),
//                                  one work-item per hit pixel
//                                  (all a light change needs)
//   shading/view_cache_probe/<part>/nearest  the view-cache pass with one part left out
//                                  (render/btf_shading.h, ShadingProbe; the image is wrong):
//                                  the material's vector reads, the cache writes, the view
//                                  samples (a fixed pattern instead), or all but the launch
//   stream_read/<pattern>          a read-only kernel summing a 512 MiB buffer: each work-item a
//                                  4 KiB block (blocks) or a grid-stride walk (strided)
//
// Times are kernel times from OpenCL profiling events (manual time). Counters: ms; MB = the
// bytes the pass must move (DeviceBtfShader::bytes_per_pass: BTF vectors and L* of every hit
// pixel, counted per pixel, no reuse assumed; plus the cache write); GBps = MB / ms; bound_ratio
// = time / (bytes / bandwidth) with the bandwidth the best stream_read pattern, measured once
// before the benchmarks (median of 15 passes). bound_ratio <= 2 is the goal of issue 6; below
// 1 means the caches serve part of the counted bytes (neighbouring pixels share texels, views
// and vertices).
//
//   POCL_MAX_PTHREAD_COUNT=2 POCL_CPU_MAX_CU_COUNT=2 POCL_AFFINITY=1
//     build/<dir>/bench/shading_bench --benchmark_repetitions=5
//       --benchmark_out=results/bench/shading-pocl.json --benchmark_out_format=json
//   (one command line)
//
// The bunny's transfer and BTF come from the stage cache ($PRTLAB_CACHE), computed on the
// first run. L* is the exact relight under `courtyard` (the sun-and-sky test environment when
// the data is missing).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "prtlab/base/build_info.h"
#include "prtlab/base/statistics.h"
#include "prtlab/geometry/scene.h"
#include "prtlab/lighting/environment_map.h"
#include "prtlab/opencl/cl_runtime.h"
#include "prtlab/render/frame_renderer.h"
#include "prtlab/storage/data_paths.h"
#include "prtlab/storage/stage_cache.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/transfer/scene_transfer.h"

namespace {

using prt::median;

struct Workload {
  std::string error;  // set when the bunny could not be prepared
  prt::Scene scene;
  prt::ShadingMaterials materials;
  prt::LocalRadiance radiance;
  prt::GBuffer gbuffer;
  std::unique_ptr<prt::Cubemap> environment;
  std::string env_name;
};

const Workload& workload() {
  static const Workload loaded = [] {
    Workload w;
    try {
      const prt::SceneDesc desc = prt::parse_scene(prt::resolve_scene("bunny"));
      prt::StageCache cache;
      prt::PrecomputeOptions popt;
      popt.show_progress = false;
      const auto st = prt::precompute_scene_transfer(desc, popt, cache);
      w.scene = prt::build_scene(desc);
      try {
        w.environment = std::make_unique<prt::Cubemap>(prt::resample_to_cubemap(
            prt::load_latlong_exr(prt::resolve_envmap("courtyard")), desc.cubemap_resolution));
        w.env_name = "courtyard";
      } catch (const prt::Error&) {
        w.environment =
            std::make_unique<prt::Cubemap>(prt::SunSky{}.to_cubemap(desc.cubemap_resolution));
        w.env_name = "sun and sky (SunSky defaults)";
      }
      w.radiance = prt::relight_exact(st.result.transfer, w.environment->light_vector());
      w.materials = prt::load_scene_materials(desc, prt::BtfParams{}, cache, "full", {});
      w.gbuffer = prt::render_gbuffer(w.scene.mesh, prt::scene_camera(w.scene, "front"));
    } catch (const std::exception& e) {
      w.error = e.what();
    }
    return w;
  }();
  return loaded;
}

// ---- memory bandwidth of the device -----------------------------------------------------------

constexpr char kStreamSource[] = R"CL(
#define BLOCK 64
__kernel PRT_WG_ATTR void stream_blocks(const uint blocks, __global const float16* restrict data,
                                        __global float* restrict out) {
  const uint b = get_global_id(0);
  PRT_GUARD(b, blocks);
  __global const float16* p = data + (size_t)b * BLOCK;
  float16 s0 = (float16)(0.0f), s1 = (float16)(0.0f);
  for (int k = 0; k < BLOCK; k += 2) {
    s0 += p[k];
    s1 += p[k + 1];
  }
  const float16 s = s0 + s1;
  out[b] = s.s0 + s.s1 + s.s2 + s.s3 + s.s4 + s.s5 + s.s6 + s.s7 + s.s8 + s.s9 + s.sa + s.sb +
           s.sc + s.sd + s.se + s.sf;
}
__kernel PRT_WG_ATTR void stream_strided(const uint n, const uint items,
                                         __global const float4* restrict data,
                                         __global float* restrict out) {
  const uint i = get_global_id(0);
  PRT_GUARD(i, items);
  float4 s = (float4)(0.0f);
  for (uint k = i; k < n; k += items) s += data[k];
  out[i] = s.x + s.y + s.z + s.w;
}
)CL";

constexpr std::size_t kStreamBytes = std::size_t{512} << 20;
constexpr std::size_t kBlockBytes = 64 * 16 * sizeof(float);

struct Stream {
  cl::Buffer data, out;
  cl::Kernel blocks, strided;
  std::size_t block_count = kStreamBytes / kBlockBytes;
  std::size_t float4s = kStreamBytes / 16;
  std::size_t strided_items = 0;
};

Stream& stream(prt::ClContext& ctx) {
  static Stream made = [&] {
    Stream s;
    const auto program = prt::build_program_source(ctx, "stream_read", kStreamSource);
    s.blocks = prt::make_kernel(program, "stream_blocks");
    s.strided = prt::make_kernel(program, "stream_strided");
    s.data = prt::make_buffer(ctx, kStreamBytes, CL_MEM_READ_ONLY, "stream array");
    std::vector<float> ones(kStreamBytes / sizeof(float), 1.0f);
    prt::write_buffer(ctx, s.data, ones.data(), kStreamBytes, "stream array");
    // Enough work-items to fill any device (a multiple of the work-group size).
    s.strided_items = std::size_t{1} << 18;
    s.out = prt::make_buffer(ctx, std::max(s.block_count, s.strided_items) * sizeof(float),
                             CL_MEM_WRITE_ONLY, "stream sums");
    return s;
  }();
  return made;
}

double event_ms(cl::Event& e) {
  e.wait();
  return static_cast<double>(e.getProfilingInfo<CL_PROFILING_COMMAND_END>() -
                             e.getProfilingInfo<CL_PROFILING_COMMAND_START>()) *
         1e-6;
}

double stream_pass_ms(prt::ClContext& ctx, bool strided) {
  Stream& s = stream(ctx);
  cl::Event e;
  if (strided) {
    prt::set_args(s.strided, static_cast<cl_uint>(s.float4s), static_cast<cl_uint>(s.strided_items),
                  s.data, s.out);
    e = prt::launch(ctx, "stream_strided", s.strided, prt::LaunchRange::linear(s.strided_items));
  } else {
    prt::set_args(s.blocks, static_cast<cl_uint>(s.block_count), s.data, s.out);
    e = prt::launch(ctx, "stream_blocks", s.blocks, prt::LaunchRange::linear(s.block_count));
  }
  return event_ms(e);
}

// GB/s of the faster pattern, median of 15 passes each.
double measured_bandwidth(prt::ClContext& ctx) {
  static const double gbps = [&] {
    double best = 0.0;
    for (const bool strided : {false, true}) {
      stream_pass_ms(ctx, strided);  // warm-up
      std::vector<double> ms;
      for (int i = 0; i < 15; ++i) ms.push_back(stream_pass_ms(ctx, strided));
      best = std::max(best, static_cast<double>(kStreamBytes) / (median(ms) * 1e6));
    }
    return best;
  }();
  return gbps;
}

void BM_stream(benchmark::State& state, bool strided) {
  prt::ClContext* ctx = prt::default_context();
  if (!ctx) return state.SkipWithError("no OpenCL device");
  for (auto _ : state) state.SetIterationTime(stream_pass_ms(*ctx, strided) * 1e-3);
  state.counters["GBps"] = benchmark::Counter(static_cast<double>(kStreamBytes) * 1e-9,
                                              benchmark::Counter::kIsIterationInvariantRate);
}

// ---- shading passes -------------------------------------------------------------------------

enum class Pass { kSingle, kViewCache, kCachedShade };

void BM_shading(benchmark::State& state, Pass pass, prt::TexelFilter filter,
                prt::ShadingProbe probe = prt::ShadingProbe::kNone) {
  prt::ClContext* ctx = prt::default_context();
  if (!ctx) return state.SkipWithError("no OpenCL device");
  const Workload& w = workload();
  if (!w.error.empty()) return state.SkipWithError(w.error.c_str());
  prt::ShadingOptions o;
  o.filter = filter;
  o.cache_view_vectors = pass != Pass::kSingle;
  o.probe = probe;
  prt::DeviceBtfShader shader(*ctx, w.scene.mesh, w.materials, w.environment.get(), o);
  shader.set_gbuffer(w.gbuffer);
  shader.set_radiance(w.radiance);
  shader.shade();  // warm-up (and builds the view cache)
  const auto bytes = shader.bytes_per_pass();
  std::uint64_t pass_bytes = 0;
  std::vector<double> ms;
  for (auto _ : state) {
    double t = 0;
    switch (pass) {
      case Pass::kSingle:
        t = shader.shade();
        pass_bytes = bytes.single_pass;
        break;
      case Pass::kViewCache: {
        state.PauseTiming();
        shader.set_gbuffer(w.gbuffer);  // invalidates the cache (host work, not timed)
        state.ResumeTiming();
        shader.shade();
        t = shader.last_view_cache_ms();
        pass_bytes = bytes.view_cache;
        break;
      }
      case Pass::kCachedShade:
        t = shader.shade();
        pass_bytes = bytes.cached_shade;
        break;
    }
    ms.push_back(t);
    state.SetIterationTime(t * 1e-3);
  }
  const double med = median(ms);
  const double gbps = measured_bandwidth(*ctx);
  state.counters["ms"] = med;
  state.counters["MB"] = static_cast<double>(pass_bytes) * 1e-6;
  state.counters["GBps"] = static_cast<double>(pass_bytes) / (med * 1e6);
  state.counters["bound_ratio"] = med / (static_cast<double>(pass_bytes) / (gbps * 1e6));
  state.counters["hit_pixels"] = static_cast<double>(shader.hit_pixels());
}

// ---- the view change's host stages ------------------------------------------------------------

// The G-buffer of the bunny's front view traced into a reused GBuffer (as FrameRenderer does).
void BM_gbuffer(benchmark::State& state, prt::PrimaryRays rays) {
  const Workload& w = workload();
  if (!w.error.empty()) return state.SkipWithError(w.error.c_str());
  const prt::GBufferTracer tracer(w.scene.mesh);
  const prt::Camera cam = prt::scene_camera(w.scene, "front");
  prt::GBuffer g;
  tracer.trace(cam, g, rays);
  for (auto _ : state) {
    tracer.trace(cam, g, rays);
    benchmark::DoNotOptimize(g.triangle.data());
  }
  state.counters["hit_pixels"] = static_cast<double>(g.hit_count());
}

// DeviceBtfShader::set_gbuffer: compaction to the hit slots, the misses' background pixels, the
// upload.
void BM_gbuffer_upload(benchmark::State& state) {
  prt::ClContext* ctx = prt::default_context();
  if (!ctx) return state.SkipWithError("no OpenCL device");
  const Workload& w = workload();
  if (!w.error.empty()) return state.SkipWithError(w.error.c_str());
  prt::DeviceBtfShader shader(*ctx, w.scene.mesh, w.materials, w.environment.get());
  shader.set_gbuffer(w.gbuffer);
  for (auto _ : state) {
    shader.set_gbuffer(w.gbuffer);
    ctx->queue().finish();
  }
}

void register_benchmarks() {
  benchmark::RegisterBenchmark(
      "gbuffer/single_rays", [](benchmark::State& s) { BM_gbuffer(s, prt::PrimaryRays::kSingle); })
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime();
  benchmark::RegisterBenchmark(
      "gbuffer/packets", [](benchmark::State& s) { BM_gbuffer(s, prt::PrimaryRays::kPackets); })
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime();
  benchmark::RegisterBenchmark(
      "gbuffer/raster", [](benchmark::State& s) { BM_gbuffer(s, prt::PrimaryRays::kRaster); })
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime();
  benchmark::RegisterBenchmark("gbuffer/upload", BM_gbuffer_upload)
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime();
  for (const auto& [fname, filter] : {std::pair{"nearest", prt::TexelFilter::kNearest},
                                      std::pair{"bilinear", prt::TexelFilter::kBilinear}}) {
    for (const auto& [pname, pass] :
         {std::pair{"single_pass", Pass::kSingle}, std::pair{"view_cache", Pass::kViewCache},
          std::pair{"cached_shade", Pass::kCachedShade}}) {
      benchmark::RegisterBenchmark(
          (std::string("shading/") + pname + "/" + fname).c_str(),
          [pass = pass, filter = filter](benchmark::State& s) { BM_shading(s, pass, filter); })
          ->UseManualTime()
          ->Unit(benchmark::kMillisecond);
    }
  }
  // The view-change kernel with one of its parts left out (ShadingProbe; the image is wrong):
  // what each part costs, by difference with shading/view_cache/nearest.
  for (const auto& [name, probe] : {std::pair{"no_vector_reads", prt::ShadingProbe::kNoVectorReads},
                                    std::pair{"no_cache_writes", prt::ShadingProbe::kNoCacheWrites},
                                    std::pair{"fixed_views", prt::ShadingProbe::kFixedViews},
                                    std::pair{"launch_only", prt::ShadingProbe::kLaunchOnly}}) {
    benchmark::RegisterBenchmark(
        (std::string("shading/view_cache_probe/") + name + "/nearest").c_str(),
        [probe = probe](benchmark::State& s) {
          BM_shading(s, Pass::kViewCache, prt::TexelFilter::kNearest, probe);
        })
        ->UseManualTime()
        ->Unit(benchmark::kMillisecond);
  }
  benchmark::RegisterBenchmark("stream_read/blocks",
                               [](benchmark::State& s) { BM_stream(s, false); })
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("stream_read/strided",
                               [](benchmark::State& s) { BM_stream(s, true); })
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  register_benchmarks();
  prt::ClContext* ctx = prt::default_context();
  const auto& build = prt::build_info();
  benchmark::AddCustomContext("prtlab_version", build.version);
  benchmark::AddCustomContext("git_hash", build.git_hash);
  benchmark::AddCustomContext("build_type", build.build_type);
  benchmark::AddCustomContext("machine", prt::machine_description());
  benchmark::AddCustomContext("opencl_device", ctx ? ctx->info().label() : "none");
  const Workload& w = workload();
  if (w.error.empty()) {
    benchmark::AddCustomContext(
        "workload", fmt::format("bunny front view {} x {}, {} hit pixels, {} vertices, M = {}, "
                                "BTF {} {} x {} texels x {} views, L* under {}",
                                w.gbuffer.width, w.gbuffer.height, w.gbuffer.hit_count(),
                                w.scene.mesh.positions.size(), w.radiance.dim,
                                w.materials.part_material[0]->sampling().material,
                                w.materials.part_material[0]->sampling().resolution,
                                w.materials.part_material[0]->sampling().resolution,
                                w.materials.part_material[0]->sampling().view_count(), w.env_name));
  }
  if (ctx)
    benchmark::AddCustomContext("read_bandwidth_GBps",
                                fmt::format("{:.2f}", measured_bandwidth(*ctx)));
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
