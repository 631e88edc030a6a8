// Clustered PCA (core/include/prtlab/numeric/clustered_pca.h, backend `cpca`) on a real
// transfer: the time of each phase and the speed of the classification product against the
// machine's measured peak and against the straightforward classification, in one process.
//
//   cpca/compress/<method>/<clusters>x<vectors>  one full clustered_pca() run (Iterations(1)):
//        counters vq_s, classify_s, pca_s, weights_s (phase wall-clock seconds), passes,
//        classify_GFLOPs (2 nnz K per pass / classification seconds), peak_GFLOPs (a
//        register-resident multiply-add stream on every thread), pct_peak, rel_frobenius.
//   cpca/classify/fused    one classification pass as clustered_pca runs it: per row one
//        sparse x dense product with every cluster's mean and vectors stacked row-major
//        (contiguous axpys, an AVX2+FMA clone where the CPU has it), then the errors
//   cpca/classify/naive    the same errors from one sparse dot product per row and
//        representative against column-major representatives (what a k-means assignment
//        loop does), the baseline the fused pass is measured against
//
//   PRTLAB_BENCH_SCENE=chair build/release/bench/clustered_pca_bench
//       --benchmark_out=results/bench/cpca/compress-chair.json --benchmark_out_format=json
//
// The scene (default chair) comes through the stage cache ($PRTLAB_CACHE); PRTLAB_BENCH_METHOD
// (iterative), PRTLAB_BENCH_CLUSTERS (32) and PRTLAB_BENCH_VECTORS (8) set the compression.
#include <benchmark/benchmark.h>
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <string>

#include "prtlab/compress/backend_input.h"
#include "prtlab/geometry/scene.h"
#include "prtlab/numeric/clustered_pca.h"
#include "prtlab/numeric/row_products.h"
#include "prtlab/storage/data_paths.h"
#include "prtlab/storage/stage_cache.h"

namespace {

std::string env_or(const char* name, const char* fallback) {
  const char* v = std::getenv(name);
  return v && *v ? v : fallback;
}

struct Workload {
  std::string scene;
  prt::TransferMatrix transfer;
  prt::RowSet rows() const {
    if (transfer.narrow_columns())
      return prt::RowSet::csr(transfer.cols(), transfer.row_offsets(), transfer.columns16(),
                              transfer.counts(), transfer.scale());
    return prt::RowSet::csr(transfer.cols(), transfer.row_offsets(), transfer.columns32(),
                            transfer.counts(), transfer.scale());
  }
};

const Workload& workload() {
  static const Workload w = [] {
    Workload x;
    x.scene = env_or("PRTLAB_BENCH_SCENE", "chair");
    const prt::SceneDesc desc = prt::parse_scene(prt::resolve_scene(x.scene));
    prt::StageCache cache;
    prt::PreparedScene s = prt::prepare_scene(desc, prt::BackendInputs{}, cache);
    x.transfer = std::move(s.transfer.result.transfer);
    return x;
  }();
  return w;
}

prt::CpcaMethod method_from_env() {
  const std::string m = env_or("PRTLAB_BENCH_METHOD", "iterative");
  if (m == "static") return prt::CpcaMethod::kStatic;
  if (m == "adaptive") return prt::CpcaMethod::kAdaptive;
  return prt::CpcaMethod::kIterative;
}

double peak_gflops() {
  static const double peak = [] {
    const int threads = tbb::this_task_arena::max_concurrency();
    std::vector<double> each(static_cast<std::size_t>(threads));
    tbb::parallel_for(0, threads, [&](int t) {
      each[static_cast<std::size_t>(t)] = prt::measured_fma_gflops_per_thread(0.3);
    });
    double sum = 0;
    for (double g : each) sum += g;
    return sum;
  }();
  return peak;
}

void BM_Compress(benchmark::State& state) {
  const Workload& w = workload();
  prt::ClusteredPcaOptions o;
  o.clusters = std::stoi(env_or("PRTLAB_BENCH_CLUSTERS", "32"));
  o.components = std::stoi(env_or("PRTLAB_BENCH_VECTORS", "8"));
  o.method = method_from_env();
  o.seed = 1;
  prt::ClusteredPca r;
  for (auto _ : state) r = prt::clustered_pca(w.rows(), o);
  const prt::CpcaPhaseTimes& t = r.times;
  const double gflops = t.classify > 0 ? t.classify_flops / t.classify * 1e-9 : 0.0;
  state.counters["vq_s"] = t.vq;
  state.counters["classify_s"] = t.classify;
  state.counters["pca_s"] = t.pca;
  state.counters["weights_s"] = t.weights;
  state.counters["passes"] = t.classify_passes;
  state.counters["classify_GFLOPs"] = gflops;
  state.counters["peak_GFLOPs"] = peak_gflops();
  state.counters["pct_peak"] = 100.0 * gflops / peak_gflops();
  state.counters["rel_frobenius"] = std::sqrt(r.squared_error / r.total_squared_norm);
  state.SetLabel(fmt::format("{}: {} rows, nnz {}, {} clusters x {} vectors", w.scene,
                             w.transfer.rows(), w.transfer.nnz(), o.clusters, o.components));
}

// A plausible model to classify against: k-means-like means (random rows of T) and random
// orthonormal-ish vectors; the speed does not depend on how good the model is.
struct Model {
  int clusters = 32, vectors = 8;
  prt::RowMajorMatrixXf stacked;  // N x K, the fused layout
  Eigen::MatrixXf columns;        // N x K column-major, the naive layout
  std::vector<double> mean_sq;
  std::vector<double> mean_dot;
};

const Model& model() {
  static const Model m = [] {
    Model x;
    const Workload& w = workload();
    const auto n = static_cast<Eigen::Index>(w.transfer.cols());
    const int k = x.clusters * (x.vectors + 1);
    std::mt19937_64 rng(7);
    std::normal_distribution<float> g;
    x.stacked.resize(n, k);
    for (Eigen::Index i = 0; i < x.stacked.size(); ++i) x.stacked.data()[i] = 0.01f * g(rng);
    x.columns = x.stacked;
    x.mean_sq.assign(static_cast<std::size_t>(x.clusters), 1.0);
    x.mean_dot.assign(static_cast<std::size_t>(k), 0.0);
    return x;
  }();
  return m;
}

template <class Product>
void classify_pass(benchmark::State& state, Product&& product) {
  const Workload& w = workload();
  const Model& m = model();
  const prt::RowSet rows = w.rows();
  const Eigen::VectorXd norms = prt::row_squared_norms(rows);
  const std::size_t width = static_cast<std::size_t>(m.stacked.cols());
  const std::size_t per = static_cast<std::size_t>(m.vectors + 1);
  std::vector<std::uint32_t> best(rows.rows());
  for (auto _ : state) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows.rows(), 256), [&](const auto& r) {
      std::vector<float> y(width);
      for (std::size_t p = r.begin(); p != r.end(); ++p) {
        product(rows, p, y);
        double lo = std::numeric_limits<double>::infinity();
        std::uint32_t arg = 0;
        for (std::size_t c = 0; c < static_cast<std::size_t>(m.clusters); ++c) {
          double e = norms[static_cast<Eigen::Index>(p)] - 2.0 * y[c * per] + m.mean_sq[c];
          for (std::size_t j = c * per + 1; j < (c + 1) * per; ++j) {
            const double d = y[j] - m.mean_dot[j];
            e -= d * d;
          }
          if (e < lo) {
            lo = e;
            arg = static_cast<std::uint32_t>(c);
          }
        }
        best[p] = arg;
      }
    });
    benchmark::DoNotOptimize(best.data());
  }
  const double flops = 2.0 * static_cast<double>(w.transfer.nnz()) * static_cast<double>(width);
  state.counters["GFLOPs"] =
      benchmark::Counter(flops * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["peak_GFLOPs"] = peak_gflops();
}

void BM_ClassifyFused(benchmark::State& state) {
  const Model& m = model();
  classify_pass(state, [&](const prt::RowSet& rows, std::size_t p, std::vector<float>& y) {
    prt::multiply_row(rows, p, m.stacked, y);
  });
}

void BM_ClassifyNaive(benchmark::State& state) {
  const Model& m = model();
  const Workload& w = workload();
  const prt::TransferMatrix& t = w.transfer;
  const float scale = static_cast<float>(t.scale());
  classify_pass(state, [&](const prt::RowSet&, std::size_t p, std::vector<float>& y) {
    const std::uint32_t b = t.row_offsets()[p], e = t.row_offsets()[p + 1];
    for (Eigen::Index k = 0; k < m.columns.cols(); ++k) {
      const float* col = m.columns.data() + k * m.columns.rows();
      float s = 0.f;
      for (std::uint32_t i = b; i < e; ++i) s += t.counts()[i] * scale * col[t.column(i)];
      y[static_cast<std::size_t>(k)] = s;
    }
  });
}

BENCHMARK(BM_Compress)->Name("cpca/compress")->Iterations(1)->Unit(benchmark::kSecond);
BENCHMARK(BM_ClassifyFused)
    ->Name("cpca/classify/fused")
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);
BENCHMARK(BM_ClassifyNaive)
    ->Name("cpca/classify/naive")
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
