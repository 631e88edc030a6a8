// Every registered material backend compressing a BTF whose ABRDFs have 4,096 samples (8 x 8
// views x 8 x 8 lights, the count of Suykens et al. 2003 section 4.4: HF 33 s and CMF 8 s per
// ABRDF and colour channel on an AMD XP 2000+), on one thread, through the registry: the
// backend's whole compress() (set-up, every texel's factorisation, normalisation, clustering
// off, the error against the BTF), divided by texels x 3 channels.
//
//   material/<backend>/<label>   counters: ms_per_abrdf_channel, texels; labels: cmf paper-chain
//        (halfway = mean, no refinement, no scale refit), svd, project (no refinement),
//        defaults; hf paper (no scale refit), defaults (float factors, no clustering); svd abrdf
//        (rank 4 per texel) and texel_pca (rank 8 over the texels' Gram matrix, the one of
//        these that solves a dense eigenproblem: numeric/symmetric_eigen.h).
//
//   build/release/bench/material_factorization_bench
// PRTLAB_BENCH_TEXELS (default 256, a square) sets the texel count; the per-BTF set-up (the
// GSHD matrix, HF's factorised system) is amortised over them as in a real compression.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "prtlab/btf/btf_generator.h"
#include "prtlab/btf/btf_materials.h"
#include "prtlab/compress/material_registry.h"

namespace {

std::shared_ptr<const prt::Btf> checker() {
  static const auto btf = [] {
    const char* env = std::getenv("PRTLAB_BENCH_TEXELS");
    const int texels = env && *env ? std::atoi(env) : 256;
    prt::BtfParams p;
    p.resolution = std::max(1, static_cast<int>(std::lround(std::sqrt(texels))));
    p.view_side = 8;
    p.light_side = 8;
    p.supersampling = 1;
    p.geometry_grid = 64;
    return std::make_shared<const prt::Btf>(
        prt::generate_btf(prt::make_btf_material("checker", 64), p));
  }();
  return btf;
}

void compress(benchmark::State& state, std::string backend,
              std::map<std::string, std::string> params) {
  const tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const auto btf = checker();
  double ms = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    auto m = prt::compress_material(backend, params, btf);
    benchmark::DoNotOptimize(m);
    ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }
  state.counters["texels"] = btf->texel_count();
  state.counters["ms_per_abrdf_channel"] =
      benchmark::Counter(ms / (btf->texel_count() * 3.0), benchmark::Counter::kAvgIterations);
}

const int registered = [] {
  using Params = std::map<std::string, std::string>;
  const auto fp = [](Params extra) {
    extra["clusters"] = "0";
    extra["quantize"] = "false";
    return extra;
  };
  for (const auto& [backend, params, label] :
       std::vector<std::tuple<std::string, Params, std::string>>{
           {"cmf", fp({{"halfway", "mean"}, {"refine", "0"}, {"refit_scale", "false"}}),
            "paper-chain"},
           {"cmf", fp({{"halfway", "svd"}, {"refine", "0"}}), "svd"},
           {"cmf", fp({{"halfway", "project"}, {"refine", "0"}}), "project"},
           {"cmf", fp({}), "defaults"},
           {"hf", fp({{"refit_scale", "false"}}), "paper"},
           {"hf", fp({}), "defaults"},
           {"svd", Params{{"rank", "4"}}, "abrdf"},
           {"svd", Params{{"mode", "texel_pca"}, {"rank", "8"}}, "texel_pca"}})
    benchmark::RegisterBenchmark(("material/" + backend + "/" + label).c_str(), compress, backend,
                                 params)
        ->Unit(benchmark::kMillisecond)
        ->MinTime(2.0);
  return 0;
}();

}  // namespace

BENCHMARK_MAIN();
