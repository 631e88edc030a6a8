// T's rows projected onto uniform Gaussian SRBFs (Tsai and Shih 2006, section 5.1;
// core/include/prtlab/sphere/srbf_projection.h), the first stage of the srbf-cta backend: the
// squared-error ratio of the SRBF representation alone (the paper's "SE ratio (SRBF)", 1.23 %
// to 1.41 % on its data) and the projection time, per SRBF count.
//
//   srbf/project/<count>  projects a fixed random sample of T's rows (PRTLAB_BENCH_ROWS, 4000;
//        seed 1) onto <count> icosphere SRBFs with the bandwidth of uniform_gaussian_bandwidth
//        (sigma = pi/40 at 642) and ridge 1e-6; counters: se_ratio (sum over the sampled rows of
//        |t~ - t|^2 over sum |t|^2, t~ evaluated at the pixel centres), gram_condition,
//        condition (with the ridge), setup_s (Gram, its factorisation, the pixel weights),
//        us_per_row (the projection alone: b from the row's non-zeros, then the LDLT solve; the
//        error evaluation is not timed), all_rows_s (us_per_row x every row of T).
//
//   PRTLAB_BENCH_SCENE=bunny build/release/bench/srbf_projection_bench
#include <benchmark/benchmark.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cstdlib>
#include <random>
#include <string>

#include "prtlab/compress/backend_input.h"
#include "prtlab/geometry/scene.h"
#include "prtlab/lighting/srbf_light.h"
#include "prtlab/sphere/icosphere.h"
#include "prtlab/sphere/srbf_projection.h"
#include "prtlab/storage/data_paths.h"
#include "prtlab/storage/stage_cache.h"

namespace {

std::string env_or(const char* name, const char* fallback) {
  const char* v = std::getenv(name);
  return v && *v ? v : fallback;
}

struct Workload {
  prt::TransferMatrix transfer;
  std::vector<std::size_t> rows;
};

const Workload& workload() {
  static const Workload w = [] {
    Workload x;
    const prt::SceneDesc desc =
        prt::parse_scene(prt::resolve_scene(env_or("PRTLAB_BENCH_SCENE", "bunny")));
    prt::StageCache cache;
    x.transfer =
        std::move(prt::prepare_scene(desc, prt::BackendInputs{}, cache).transfer.result.transfer);
    const std::size_t sample = std::stoul(env_or("PRTLAB_BENCH_ROWS", "4000"));
    std::mt19937_64 rng(1);
    std::uniform_int_distribution<std::size_t> pick(0, x.transfer.rows() - 1);
    while (x.rows.size() < sample) {
      const std::size_t r = pick(rng);
      if (x.transfer.row_offsets()[r + 1] > x.transfer.row_offsets()[r]) x.rows.push_back(r);
    }
    return x;
  }();
  return w;
}

void BM_Project(benchmark::State& state) {
  const Workload& w = workload();
  const int count = static_cast<int>(state.range(0));
  const prt::CubemapLayout layout(32);
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    prt::SrbfBasis basis;
    basis.centres = prt::icosphere_vertices(prt::icosphere_level_for_count(count));
    basis.bandwidths.assign(basis.centres.size(), prt::uniform_gaussian_bandwidth(basis.centres));
    const prt::SrbfProjector p(basis, layout, 1e-6);
    const auto t1 = std::chrono::steady_clock::now();
    std::vector<Eigen::VectorXd> coeffs(w.rows.size());
    const auto entries = [&](std::size_t i, std::vector<std::uint32_t>& cols,
                             std::vector<double>& vals) {
      const auto& t = w.transfer;
      for (std::uint32_t e = t.row_offsets()[w.rows[i]]; e < t.row_offsets()[w.rows[i] + 1]; ++e) {
        cols.push_back(t.column(e));
        vals.push_back(t.value(e));
      }
    };
    tbb::parallel_for(std::size_t{0}, w.rows.size(), [&](std::size_t i) {
      std::vector<std::uint32_t> cols;
      std::vector<double> vals;
      entries(i, cols, vals);
      coeffs[i] = p.project_sparse(cols, vals);
    });
    const auto t2 = std::chrono::steady_clock::now();
    // The error, not timed: t~ at the pixel centres, (W c)_k / Omega_k.
    std::vector<double> err(w.rows.size()), norm(w.rows.size());
    tbb::parallel_for(std::size_t{0}, w.rows.size(), [&](std::size_t i) {
      std::vector<std::uint32_t> cols;
      std::vector<double> vals;
      entries(i, cols, vals);
      const Eigen::VectorXd approx = p.pixel_weights() * coeffs[i];
      std::vector<double> exact(static_cast<std::size_t>(layout.pixel_count()), 0.0);
      for (std::size_t e = 0; e < cols.size(); ++e) exact[cols[e]] = vals[e];
      double se = 0, n2 = 0;
      for (int k = 0; k < layout.pixel_count(); ++k) {
        const double d = approx[k] / layout.solid_angle(k) - exact[static_cast<std::size_t>(k)];
        se += d * d;
        n2 += exact[static_cast<std::size_t>(k)] * exact[static_cast<std::size_t>(k)];
      }
      err[i] = se;
      norm[i] = n2;
    });
    double se = 0, n2 = 0;
    for (std::size_t i = 0; i < err.size(); ++i) se += err[i], n2 += norm[i];
    const double per_row = std::chrono::duration<double>(t2 - t1).count() / w.rows.size();
    state.counters["se_ratio"] = se / n2;
    state.counters["gram_condition"] = p.gram_condition_number();
    state.counters["condition"] = p.condition_number();
    state.counters["setup_s"] = std::chrono::duration<double>(t1 - t0).count();
    state.counters["us_per_row"] = 1e6 * per_row;
    state.counters["all_rows_s"] = per_row * static_cast<double>(w.transfer.rows());
    state.counters["bandwidth"] = basis.bandwidths.front();
  }
}
BENCHMARK(BM_Project)
    ->Name("srbf/project")
    ->Arg(162)
    ->Arg(642)
    ->Arg(2562)
    ->Iterations(1)
    ->Unit(benchmark::kSecond);

}  // namespace

BENCHMARK_MAIN();
