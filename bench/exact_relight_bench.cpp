// Exact relight L* = T L on the bunny (scenes/bunny.toml: 3,286 vertices, R = 32, S = 8, s = 2):
// our C++ CSR product (TBB, and one thread) against Eigen's sparse product, plus the transfer
// precomputation itself. When the bunny's data is missing, a synthetic matrix of the same
// shape (210,304 x 6,144, about 50 non-zeros per row, one per column per vertex block) stands
// in, and the benchmark context says so.
//
//   build/<dir>/bench/exact_relight_bench --benchmark_counters_tabular=true
//
// Counters: nnz/s (non-zeros per second), bytes/s (bytes of T's CSR arrays, the light and the
// output per second), vs_eigen (Eigen's time per relight divided by ours: > 1 is faster).
#include <benchmark/benchmark.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>

#include "prtlab/storage/data_paths.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/base/log.h"
#include "prtlab/transfer/random_transfer.h"
#include "prtlab/geometry/scene.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace {

using prt::Rgb;

struct BenchData {
  std::string source;
  prt::Mesh mesh;  // empty for the synthetic fallback
  prt::TransferParams params;
  prt::TransferMatrix transfer;
  prt::TransferStats stats;
  std::vector<Rgb> light;
  double eigen_seconds = 0.0;  // median time of one Eigen product
};

prt::TransferMatrix synthetic_bunny_shape(std::mt19937_64& rng) {
  prt::RandomTransferSpec spec;
  spec.vertices = 3286;
  spec.grid_side = 8;
  spec.resolution = 32;
  spec.supersampling = 2;
  spec.density = 3200.0 / 6144.0;
  return prt::random_transfer(rng(), spec);
}

BenchData make_data() {
  BenchData d;
  d.params.show_progress = false;
  std::mt19937_64 rng(20240613);
  try {
    const prt::Scene scene = prt::load_scene(prt::resolve_scene("bunny"));
    d.params.cubemap_resolution = scene.desc.cubemap_resolution;
    d.params.local_grid = scene.desc.local_grid;
    d.params.supersampling = scene.desc.supersampling;
    d.mesh = scene.mesh;
    auto result = prt::compute_transfer(d.mesh, d.params);
    d.transfer = std::move(result.transfer);
    d.stats = result.stats;
    d.source = fmt::format("bunny ({} vertices)", d.mesh.vertex_count());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bunny unavailable (%s); using a synthetic matrix of its shape\n",
                 e.what());
    d.transfer = synthetic_bunny_shape(rng);
    d.source = "synthetic 210304 x 6144, ~50 nnz/row";
  }
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  d.light.resize(d.transfer.cols());
  for (auto& l : d.light) l = {u(rng), u(rng), u(rng)};

  const prt::EigenSparseTransfer eigen(d.transfer);
  const auto x = prt::EigenSparseTransfer::to_dense(d.light);
  prt::EigenSparseTransfer::Dense y;
  std::vector<double> times;
  for (int i = 0; i < 15; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    eigen.multiply(x, y);
    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  std::nth_element(times.begin(), times.begin() + 7, times.end());
  d.eigen_seconds = times[7];
  return d;
}

const BenchData& data() {
  static const BenchData d = make_data();
  return d;
}

void add_counters(benchmark::State& state, const BenchData& d, double seconds) {
  const prt::TransferMatrix& t = d.transfer;
  const double bytes =
      static_cast<double>(t.memory_bytes() + t.cols() * sizeof(Rgb) + t.rows() * sizeof(Rgb));
  state.counters["nnz/s"] = benchmark::Counter(static_cast<double>(t.nnz()),
                                               benchmark::Counter::kIsIterationInvariantRate);
  state.counters["bytes/s"] = benchmark::Counter(
      bytes, benchmark::Counter::kIsIterationInvariantRate, benchmark::Counter::OneK::kIs1000);
  const double per = seconds / static_cast<double>(state.iterations());
  state.counters["ms"] = per * 1e3;
  state.counters["vs_eigen"] = d.eigen_seconds / per;
  state.SetLabel(d.source);
}

// Manual wall-clock timing: the products are multithreaded, so CPU time would mislead.
template <typename F>
void run_timed(benchmark::State& state, F&& f) {
  double seconds = 0.0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    state.SetIterationTime(s);
    seconds += s;
  }
  add_counters(state, data(), seconds);
}

void BM_RelightCsr(benchmark::State& state) {
  const BenchData& d = data();
  std::vector<Rgb> out(d.transfer.rows());
  run_timed(state, [&] {
    prt::relight_exact(d.transfer, d.light, out);
    benchmark::DoNotOptimize(out.data());
  });
}

void BM_RelightCsrOneThread(benchmark::State& state) {
  const BenchData& d = data();
  std::vector<Rgb> out(d.transfer.rows());
  run_timed(state, [&] {
    prt::relight_exact(d.transfer, d.light, out, prt::RelightThreads::kOne);
    benchmark::DoNotOptimize(out.data());
  });
}

void BM_RelightEigen(benchmark::State& state) {
  const BenchData& d = data();
  const prt::EigenSparseTransfer eigen(d.transfer);
  const auto x = prt::EigenSparseTransfer::to_dense(d.light);
  prt::EigenSparseTransfer::Dense y;
  run_timed(state, [&] {
    eigen.multiply(x, y);
    benchmark::DoNotOptimize(y.data());
  });
}

void BM_RelightDoubleReference(benchmark::State& state) {
  const BenchData& d = data();
  run_timed(state,
            [&] { benchmark::DoNotOptimize(prt::relight_exact_double(d.transfer, d.light)); });
}

// The precomputation of T for the bunny (skipped for the synthetic fallback).
void BM_TransferPrecompute(benchmark::State& state) {
  const BenchData& d = data();
  if (d.mesh.vertex_count() == 0) {
    state.SkipWithError("bunny data unavailable");
    return;
  }
  prt::TransferStats stats;
  for (auto _ : state) {
    auto result = prt::compute_transfer(d.mesh, d.params);
    stats = result.stats;
    state.SetIterationTime(stats.seconds_total);
    benchmark::DoNotOptimize(result.transfer.nnz());
  }
  state.counters["nnz_M"] = d.transfer.nnz() * 1e-6;
  state.counters["Mrays/s"] = stats.rays_per_second() * 1e-6;
  state.counters["Mrays"] = stats.rays_traced * 1e-6;
  state.counters["s_setup"] = stats.seconds_setup;
  state.counters["s_points"] = stats.seconds_points;
  state.counters["s_assemble"] = stats.seconds_assemble;
  state.counters["Mrays/cpu_s"] = stats.rays_per_trace_cpu_second() * 1e-6;
  state.counters["cpu_s_trace"] = stats.thread_seconds_trace;
  state.counters["cpu_s_bin"] = stats.thread_seconds_bin;
  state.counters["threads"] = stats.threads;
  state.SetLabel(d.source);
}

}  // namespace

BENCHMARK(BM_RelightCsr)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RelightCsrOneThread)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RelightEigen)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RelightDoubleReference)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TransferPrecompute)->UseManualTime()->Unit(benchmark::kSecond)->Iterations(1);

BENCHMARK_MAIN();
