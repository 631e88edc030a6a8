// The diffuse-BTF skip (docs/btf.md "Diffuse BTFs"): shading a view-independent BTF from one view
// sample against interpolating its 4 (equal) view samples, on the bunny made diffuse
// (scenes/bunny.toml with every part's BTF `lambert`: 32 x 32 texels x 144 views x M = 64,
// front view at 640 x 480). Both materials hold the same values; the second is built with
// ViewSkip::kNever (without_view_skip). Every iteration times both, alternating, so the ratio
// comes from one run under the same load:
//
//   diffuse_skip/cpp/<filter>            shade_frame_reference (C++, TBB)
//   diffuse_skip/single_pass/<filter>    DeviceBtfShader without the view cache (btf_shade_single)
//   diffuse_skip/view_change/<filter>    DeviceBtfShader with ShadingOptions::cache_view_vectors:
//                                        shade() after a new G-buffer (btf_view_cache +
//                                        btf_shade_cached; the skip's nearest pass runs the single
//                                        pass instead, DeviceBtfShader::uses_view_cache)
//   diffuse_skip/light_change/<filter>   the same shaders, shade() again (btf_shade_cached, or the
//                                        single pass where the cache is not used)
//
// Counters: skip_ms and interp_ms (medians), ratio = interp_ms / skip_ms; for the device passes
// also the bytes each pass moves (DeviceBtfShader::bytes_per_pass), the shader's device memory
// and whether each uses the view cache. The iteration time reported is the skip's.
//
//   POCL_MAX_PTHREAD_COUNT=2 POCL_CPU_MAX_CU_COUNT=2 POCL_AFFINITY=1
//     build/<dir>/bench/diffuse_skip_bench --benchmark_repetitions=3
//       --benchmark_out=results/bench/diffuse-skip/bench.json --benchmark_out_format=json
//   (one command line)
//
// The transfer and the BTF come from the stage cache ($PRTLAB_CACHE), computed on the first run.
// L* is the exact relight under `courtyard` (the sun-and-sky test environment when the data is
// missing).
#include <benchmark/benchmark.h>

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "prtlab/base/build_info.h"
#include "prtlab/base/error.h"
#include "prtlab/base/statistics.h"
#include "prtlab/btf/scene_btfs.h"
#include "prtlab/compress/material_registry.h"
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
  std::string error;  // set when the scene could not be prepared
  prt::Scene scene;
  prt::ShadingMaterials skip, interp;  // the same BTFs, with and without the view skip
  prt::LocalRadiance radiance;
  prt::GBuffer gbuffer;
  std::unique_ptr<prt::Cubemap> environment;
  std::string env_name;
  std::shared_ptr<const prt::Btf> btf;  // part 0's
};

const Workload& workload() {
  static const Workload loaded = [] {
    Workload w;
    try {
      prt::SceneDesc desc = prt::parse_scene(prt::resolve_scene("bunny"));
      for (auto& part : desc.parts) part.btf = "lambert";
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
      const auto btfs = prt::scene_part_btfs(desc, prt::BtfParams{}, cache);
      if (!btfs.front()->view_independent())
        throw prt::ParameterError("the lambert BTF is not view independent");
      std::vector<std::shared_ptr<const prt::Btf>> interpolated;
      for (const auto& b : btfs)
        interpolated.push_back(std::make_shared<const prt::Btf>(prt::without_view_skip(*b)));
      w.btf = btfs.front();
      w.skip.part_material = prt::compress_part_materials(btfs, "full", {});
      w.interp.part_material = prt::compress_part_materials(interpolated, "full", {});
      w.gbuffer = prt::render_gbuffer(w.scene.mesh, prt::scene_camera(w.scene, "front"));
    } catch (const std::exception& e) {
      w.error = e.what();
    }
    return w;
  }();
  return loaded;
}

const char* filter_name(prt::TexelFilter f) {
  return f == prt::TexelFilter::kNearest ? "nearest" : "bilinear";
}

void report(benchmark::State& state, const std::vector<double>& skip_ms,
            const std::vector<double>& interp_ms) {
  const double s = median(skip_ms), i = median(interp_ms);
  state.counters["skip_ms"] = s;
  state.counters["interp_ms"] = i;
  state.counters["ratio"] = s > 0 ? i / s : 0.0;
}

void BM_cpp(benchmark::State& state, prt::TexelFilter filter) {
  const Workload& w = workload();
  if (!w.error.empty()) return state.SkipWithError(w.error.c_str());
  prt::ShadingOptions o;
  o.filter = filter;
  auto timed = [&](const prt::ShadingMaterials& m) {
    const auto t0 = std::chrono::steady_clock::now();
    const prt::RgbImage image =
        prt::shade_frame_reference(w.gbuffer, w.scene.mesh, m, w.radiance, w.environment.get(), o);
    benchmark::DoNotOptimize(image.pixels.data());
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  };
  timed(w.skip);  // warm-up
  timed(w.interp);
  std::vector<double> skip_ms, interp_ms;
  for (auto _ : state) {
    skip_ms.push_back(timed(w.skip));
    interp_ms.push_back(timed(w.interp));
    state.SetIterationTime(skip_ms.back() * 1e-3);
  }
  report(state, skip_ms, interp_ms);
}

enum class Pass { kSingle, kViewChange, kLightChange };

// One timed frame's shading of `shader` (a new G-buffer first for kViewChange: host work,
// untimed).
double pass_ms(prt::DeviceBtfShader& shader, const prt::GBuffer& g, Pass pass) {
  if (pass == Pass::kViewChange) shader.set_gbuffer(g);
  return shader.shade();
}

std::uint64_t pass_bytes(const prt::DeviceBtfShader& shader, Pass pass) {
  const auto b = shader.bytes_per_pass();
  if (!shader.uses_view_cache()) return b.single_pass;
  return pass == Pass::kViewChange ? b.view_cache + b.cached_shade : b.cached_shade;
}

void BM_device(benchmark::State& state, Pass pass, prt::TexelFilter filter) {
  prt::ClContext* ctx = prt::default_context();
  if (!ctx) return state.SkipWithError("no OpenCL device");
  const Workload& w = workload();
  if (!w.error.empty()) return state.SkipWithError(w.error.c_str());
  prt::ShadingOptions o;
  o.filter = filter;
  o.cache_view_vectors = pass != Pass::kSingle;
  prt::DeviceBtfShader skip(*ctx, w.scene.mesh, w.skip, w.environment.get(), o);
  prt::DeviceBtfShader interp(*ctx, w.scene.mesh, w.interp, w.environment.get(), o);
  for (auto* s : {&skip, &interp}) {
    s->set_gbuffer(w.gbuffer);
    s->set_radiance(w.radiance);
    s->shade();  // warm-up (and builds the view cache)
  }
  std::vector<double> skip_ms, interp_ms;
  for (auto _ : state) {
    skip_ms.push_back(pass_ms(skip, w.gbuffer, pass));
    interp_ms.push_back(pass_ms(interp, w.gbuffer, pass));
    state.SetIterationTime(skip_ms.back() * 1e-3);
  }
  report(state, skip_ms, interp_ms);
  state.counters["skip_MB"] = static_cast<double>(pass_bytes(skip, pass)) * 1e-6;
  state.counters["interp_MB"] = static_cast<double>(pass_bytes(interp, pass)) * 1e-6;
  state.counters["skip_device_MB"] = static_cast<double>(skip.device_bytes()) * 1e-6;
  state.counters["interp_device_MB"] = static_cast<double>(interp.device_bytes()) * 1e-6;
  state.counters["hit_pixels"] = static_cast<double>(skip.hit_pixels());
  state.counters["skip_cached"] = skip.uses_view_cache() ? 1 : 0;
  state.counters["interp_cached"] = interp.uses_view_cache() ? 1 : 0;
}

void register_benchmarks() {
  for (const auto filter : {prt::TexelFilter::kNearest, prt::TexelFilter::kBilinear}) {
    benchmark::RegisterBenchmark((std::string("diffuse_skip/cpp/") + filter_name(filter)).c_str(),
                                 [filter](benchmark::State& s) { BM_cpp(s, filter); })
        ->UseManualTime()
        ->Unit(benchmark::kMillisecond);
    for (const auto& [name, pass] :
         {std::pair{"single_pass", Pass::kSingle}, std::pair{"view_change", Pass::kViewChange},
          std::pair{"light_change", Pass::kLightChange}}) {
      benchmark::RegisterBenchmark(
          (std::string("diffuse_skip/") + name + "/" + filter_name(filter)).c_str(),
          [pass = pass, filter](benchmark::State& s) { BM_device(s, pass, filter); })
          ->UseManualTime()
          ->Unit(benchmark::kMillisecond);
    }
  }
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
        "workload",
        fmt::format("bunny (every part lambert) front view {} x {}, {} hit pixels, {} vertices, "
                    "M = {}, BTF {} {} x {} texels x {} views ({:.1f} MB), L* under {}",
                    w.gbuffer.width, w.gbuffer.height, w.gbuffer.hit_count(),
                    w.scene.mesh.positions.size(), w.radiance.dim, w.btf->material(),
                    w.btf->resolution(), w.btf->resolution(), w.btf->view_count(),
                    static_cast<double>(w.btf->bytes()) * 1e-6, w.env_name));
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
