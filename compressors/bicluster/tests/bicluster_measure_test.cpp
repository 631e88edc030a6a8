// Backend `bicluster`: measurements on a real scene, disabled by default (they need the scene's
// transfer in the stage cache and take seconds to minutes). Run by hand:
//
//   BICLUSTER_SCENE=bunny build/<dir>/tests/bicluster_measure_test
//     --gtest_also_run_disabled_tests --gtest_filter='*LossyCurve*'     (one command line)
//
// LossyCurve prints the error-vs-cost table of compressors/bicluster/README.md: for each E, the
// computation and data percentages and the relative L2 and L1 errors of L* against the exact
// double product over the evaluation lights (the `prtlab compress` evaluation).
// GatherLocality prints how many distinct biclusters blocks of rows read under several
// numberings; RowOrderReuse simulates how closely phase 2's row orders reuse P's lines (the
// "Row order" table); RelightTiming times the C++ and OpenCL relights beside the uncompressed one
// and prints the worst per-value error (BICLUSTER_THREADS, BICLUSTER_REPS,
// BICLUSTER_UNIFORM_LIGHT=1 for uniform random radiance). BICLUSTER_GROUPS and BICLUSTER_SEED
// override the defaults.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <random>

#include "bicluster/bicluster.h"
#include "bicluster/bicluster_budget.h"
#include "prtlab/base/statistics.h"
#include "prtlab/compress/backend_evaluation.h"
#include "prtlab/geometry/scene.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/sphere/cubemap.h"
#include "prtlab/storage/data_paths.h"
#include "prtlab/storage/stage_cache.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/transfer/scene_transfer.h"

namespace prt::bicluster {
namespace {

struct Loaded {
  SceneDesc desc;
  SceneTransfer st;
};

Loaded load_scene() {
  const char* name = std::getenv("BICLUSTER_SCENE");
  Loaded l;
  l.desc = parse_scene(resolve_scene(name ? name : "bunny"));
  StageCache cache;
  PrecomputeOptions options;
  options.show_progress = false;
  l.st = precompute_scene_transfer(l.desc, options, cache);
  return l;
}

int env_int(const char* name, int fallback) {
  const char* v = std::getenv(name);
  return v ? std::atoi(v) : fallback;
}

TEST(BiclusterMeasure, DISABLED_LossyCurve) {
  const Loaded l = load_scene();
  const TransferMatrix& t = l.st.result.transfer;
  const SparseCounts counts = counts_of(t);
  SearchOptions options;
  options.seed = static_cast<std::uint64_t>(env_int("BICLUSTER_SEED", 1));
  options.groups = env_int("BICLUSTER_GROUPS", kDefaultGroups);
  options.rows_per_vertex = static_cast<std::size_t>(t.local_count());
  const Biclustering lossless = search(counts, options, Progress::null());
  const auto mass = column_mass(counts);
  const auto lights = evaluation_lights(l.desc.cubemap_resolution);
  std::vector<std::vector<Vec3d>> exact;
  for (const auto& light : lights)
    exact.push_back(relight_exact_double(t, light.radiance.light_vector()));

  std::printf("scene %s: %zu rows, %zu non-zeros, seed %llu, groups %d, %zu lights\n",
              l.desc.name.c_str(), t.rows(), t.nnz(), static_cast<unsigned long long>(options.seed),
              options.groups, lights.size());
  std::printf(
      "| E | bound | computation %% | data %% | biclusters | residual terms | incidences | "
      "padding %% | rel. L2 mean | rel. L2 max | rel. L1 mean | rel. L1 max |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (double e : {0.0, 0.001, 0.003, 0.01, 0.03, 0.1, 0.3}) {
    Biclustering b = lossless;
    const BudgetResult r = drop_within_budget(b, mass, e);
    BiclusterArrays a = pack(b, t);
    a.error = e;
    a.bound = r.bound;
    const BiclusterTransfer ct(std::move(a));
    double l2_sum = 0, l2_max = 0, l1_sum = 0, l1_max = 0;
    LocalRadiance out;
    for (std::size_t i = 0; i < lights.size(); ++i) {
      ct.relight(ct.project_light(lights[i].radiance), out);
      double d2 = 0, n2 = 0, d1 = 0, n1 = 0;
      for (std::size_t j = 0; j < out.values.size(); ++j) {
        for (int c = 0; c < 3; ++c) {
          const double x = out.values[j][c], y = exact[i][j][c];
          d2 += (x - y) * (x - y);
          n2 += y * y;
          d1 += std::abs(x - y);
          n1 += std::abs(y);
        }
      }
      const double l2 = std::sqrt(d2 / n2), l1 = d1 / n1;
      EXPECT_LE(l1, r.bound * (1 + 1e-6) + 1e-6) << lights[i].name << " E " << e;
      l2_sum += l2;
      l1_sum += l1;
      l2_max = std::max(l2_max, l2);
      l1_max = std::max(l1_max, l1);
    }
    const double n = static_cast<double>(lights.size());
    const std::size_t incidences = ct.arrays().incidences();
    std::printf(
        "| %g | %.4g | %.2f | %.3f | %zu | %zu | %zu | %.1f | %.2e | %.2e | %.2e | %.2e |\n", e,
        r.bound, 100.0 * ct.flops_per_relight() / (2.0 * static_cast<double>(t.nnz())),
        100.0 * static_cast<double>(ct.storage().total_bytes()) /
            static_cast<double>(t.dense_bytes()),
        b.biclusters.size(), b.residual.size(), incidences,
        100.0 * (1.0 - static_cast<double>(incidences) /
                           static_cast<double>(ct.arrays().slice_codes.size())),
        l2_sum / n, l2_max, l1_sum / n, l1_max);
    std::fflush(stdout);
  }
}

// Locality of phase 2's gathers: per block of rows, how many distinct biclusters it reads and
// how far apart their ids are, for the search's numbering and for renumberings, with rows in
// their order or grouped by local direction j.
TEST(BiclusterMeasure, DISABLED_GatherLocality) {
  const Loaded l = load_scene();
  const TransferMatrix& t = l.st.result.transfer;
  const std::size_t m = static_cast<std::size_t>(t.local_count());
  SearchOptions options;
  options.groups = env_int("BICLUSTER_GROUPS", kDefaultGroups);
  options.rows_per_vertex = m;
  const Biclustering b = search(counts_of(t), options, Progress::null());
  const std::size_t nb = b.biclusters.size();
  std::vector<std::uint32_t> by_row(t.rows()), by_dir(t.rows());
  std::iota(by_row.begin(), by_row.end(), 0u);
  for (std::size_t i = 0; i < t.rows(); ++i)
    by_dir[i] = static_cast<std::uint32_t>((i % t.vertex_count()) * m + i / t.vertex_count());
  auto report = [&](const char* name, const std::vector<std::uint32_t>& id_of,
                    const std::vector<std::uint32_t>& rows) {
    std::vector<std::vector<std::uint32_t>> per_row(t.rows());
    for (std::size_t i = 0; i < nb; ++i)
      for (std::uint32_t j : b.biclusters[i].rows) per_row[j].push_back(id_of[i]);
    std::uint64_t big_delta = 0, deltas = 0, distinct_sum = 0, blocks = 0, u8_deltas = 0, lines = 0;
    double span_sum = 0;
    const std::size_t block = static_cast<std::size_t>(env_int("BICLUSTER_BLOCK", 2048));
    for (std::size_t j0 = 0; j0 < t.rows(); j0 += block) {
      std::vector<std::uint32_t> ids;
      for (std::size_t jj = j0; jj < std::min(t.rows(), j0 + block); ++jj) {
        auto& r = per_row[rows[jj]];
        std::sort(r.begin(), r.end());
        for (std::size_t q = 0; q < r.size(); ++q) {
          const std::uint32_t d = q == 0 ? r[q] : r[q] - r[q - 1];
          ++deltas;
          big_delta += d >= 65536;
          u8_deltas += d < 256;
        }
        ids.insert(ids.end(), r.begin(), r.end());
      }
      std::sort(ids.begin(), ids.end());
      ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
      if (ids.empty()) continue;
      ++blocks;
      distinct_sum += ids.size();
      std::vector<std::uint32_t> ls;
      for (std::uint32_t id : ids) ls.push_back(id / 4);
      ls.erase(std::unique(ls.begin(), ls.end()), ls.end());
      lines += ls.size();
      span_sum += ids.back() - ids.front();
    }
    std::printf(
        "%-26s deltas >= 2^16: %.3f %%, < 2^8: %.1f %%; per %zu-row block: %.0f ids, "
        "%.0f KB of 64-B lines, id span %.0f\n",
        name, 100.0 * big_delta / deltas, 100.0 * u8_deltas / deltas, block,
        double(distinct_sum) / blocks, 64.0 * lines / blocks / 1024, span_sum / blocks);
  };
  auto renumber = [&](auto key) {
    std::vector<std::uint32_t> order(nb);
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(),
                     [&](std::uint32_t x, std::uint32_t y) { return key(x) < key(y); });
    std::vector<std::uint32_t> renum(nb);
    for (std::size_t i = 0; i < nb; ++i) renum[order[i]] = static_cast<std::uint32_t>(i);
    return renum;
  };
  std::vector<std::uint32_t> id(nb);
  std::iota(id.begin(), id.end(), 0u);
  // Majority local direction of each bicluster, and how many of its rows have it.
  std::vector<std::uint32_t> major(nb);
  std::uint64_t in_major = 0, incid = 0;
  for (std::size_t i = 0; i < nb; ++i) {
    std::vector<int> count(m, 0);
    for (std::uint32_t j : b.biclusters[i].rows) ++count[j % m];
    const auto best = std::max_element(count.begin(), count.end());
    major[i] = static_cast<std::uint32_t>(best - count.begin());
    in_major += static_cast<std::uint64_t>(*best);
    incid += b.biclusters[i].rows.size();
  }
  std::printf("%zu biclusters, %llu incidences, %.1f %% of them in the bicluster's majority j\n",
              nb, static_cast<unsigned long long>(incid), 100.0 * in_major / incid);
  report("search order, rows", id, by_row);
  report("search order, by j", id, by_dir);
  const auto first_row = renumber([&](std::uint32_t i) { return b.biclusters[i].rows.front(); });
  report("first row, rows", first_row, by_row);
  const auto by_major = renumber(
      [&](std::uint32_t i) { return std::pair(major[i], b.biclusters[i].rows.front() / m); });
  report("majority j, by j", by_major, by_dir);
  report("majority j, rows", by_major, by_row);
  // Vertices in the order of their mean visible direction (a coarse cubemap cell), rows of a
  // vertex together; biclusters numbered by first use in that order.
  const CubemapLayout layout(l.desc.cubemap_resolution);
  for (int cells : {2, 4, 8}) {
    const CubemapLayout coarse(cells);
    std::vector<std::pair<int, std::uint32_t>> key(t.vertex_count());
    for (std::size_t v = 0; v < t.vertex_count(); ++v) {
      Vec3d mean(0.0);
      for (std::size_t i = t.row_offsets()[v * m]; i < t.row_offsets()[(v + 1) * m]; ++i)
        mean +=
            static_cast<double>(t.counts()[i]) * layout.direction(static_cast<int>(t.column(i)));
      key[v] = {glm::length(mean) > 0 ? coarse.pixel_of(mean) : -1, static_cast<std::uint32_t>(v)};
    }
    std::sort(key.begin(), key.end());
    std::vector<std::uint32_t> rows;
    for (const auto& [cell, v] : key)
      for (std::size_t j = 0; j < m; ++j) rows.push_back(static_cast<std::uint32_t>(v * m + j));
    std::vector<std::uint32_t> renum(nb, ~0u);
    std::vector<std::vector<std::uint32_t>> per_row(t.rows());
    for (std::size_t i = 0; i < nb; ++i)
      for (std::uint32_t j : b.biclusters[i].rows)
        per_row[j].push_back(static_cast<std::uint32_t>(i));
    std::uint32_t next = 0;
    for (std::uint32_t j : rows)
      for (std::uint32_t i : per_row[j])
        if (renum[i] == ~0u) renum[i] = next++;
    report(fmt::format("direction {}, first use", cells).c_str(), renum, rows);
  }
}

void relight_timing();

// Reuse of P's lines in phase 2 under row orders (compressors/bicluster/README.md, "Row order"): an
// LRU stack simulation of the gathers, in 64-byte lines of P (4 products), with biclusters
// numbered by first use in each order as pack() numbers them. Prints the share of gathers whose
// line was last read within 32 KiB (512 lines) and beyond 256 KiB (4,096 lines) of other lines.
TEST(BiclusterMeasure, DISABLED_RowOrderReuse) {
  const Loaded l = load_scene();
  const TransferMatrix& t = l.st.result.transfer;
  SearchOptions options;
  options.groups = env_int("BICLUSTER_GROUPS", kDefaultGroups);
  options.rows_per_vertex = static_cast<std::size_t>(t.local_count());
  const BiclusterArrays a = pack(search(counts_of(t), options, Progress::null()), t);
  const std::size_t rows = a.rows(), m = static_cast<std::size_t>(a.local_count);
  std::vector<std::vector<std::uint32_t>> ids(rows);
  for (std::size_t s = 0; s < a.slice_count(); ++s) {
    for (int lane = 0; lane < kSliceRows; ++lane) {
      const std::uint32_t row = a.slice_rows[s * kSliceRows + static_cast<std::size_t>(lane)];
      a.for_each_id(s, lane, [&](std::uint32_t id) { ids[row].push_back(id); });
    }
  }
  std::size_t gathers = 0;
  for (const auto& r : ids) gathers += r.size();
  auto simulate = [&](const char* name, const std::vector<std::uint32_t>& order) {
    std::vector<std::int64_t> renumber(a.bicluster_count(), -1);
    std::int64_t next = 0;
    for (std::uint32_t row : order)
      for (std::uint32_t id : ids[row])
        if (renumber[id] < 0) renumber[id] = next++;
    // Fenwick tree over access times: distinct lines since a line's last access.
    std::vector<int> tree(gathers + 1, 0);
    auto add = [&](std::size_t i, int v) {
      for (++i; i < tree.size(); i += i & (~i + 1)) tree[i] += v;
    };
    auto prefix = [&](std::size_t i) {  // sum over times [0, i)
      int sum = 0;
      for (; i > 0; i -= i & (~i + 1)) sum += tree[i];
      return sum;
    };
    std::vector<std::int64_t> last((static_cast<std::size_t>(next) + 3) / 4, -1);
    std::size_t time = 0, near = 0, far = 0;
    for (std::uint32_t row : order) {
      for (std::uint32_t id : ids[row]) {
        const auto line = static_cast<std::size_t>(renumber[id] / 4);
        if (last[line] >= 0) {
          const int distance = prefix(time) - prefix(static_cast<std::size_t>(last[line]) + 1);
          near += distance < 512;
          far += distance >= 4096;
          add(static_cast<std::size_t>(last[line]), -1);
        }
        add(time, 1);
        last[line] = static_cast<std::int64_t>(time++);
      }
    }
    std::printf("%-44s within 32 KiB %5.1f %%, beyond 256 KiB %5.1f %%\n", name,
                100.0 * static_cast<double>(near) / static_cast<double>(gathers),
                100.0 * static_cast<double>(far) / static_cast<double>(gathers));
  };
  std::vector<std::uint32_t> stored(a.slice_rows.begin(), a.slice_rows.end());
  std::erase_if(stored, [&](std::uint32_t row) { return row >= rows; });
  std::vector<std::uint32_t> by_vertex(rows);  // version 2: per vertex, longer rows first
  std::iota(by_vertex.begin(), by_vertex.end(), 0u);
  for (std::size_t v = 0; v < a.vertices; ++v) {
    std::stable_sort(
        by_vertex.begin() + static_cast<std::ptrdiff_t>(v * m),
        by_vertex.begin() + static_cast<std::ptrdiff_t>((v + 1) * m),
        [&](std::uint32_t x, std::uint32_t y) { return ids[x].size() > ids[y].size(); });
  }
  std::vector<std::uint32_t> by_smallest = by_vertex;  // by the row's smallest stored id
  std::stable_sort(by_smallest.begin(), by_smallest.end(), [&](std::uint32_t x, std::uint32_t y) {
    const auto key = [&](std::uint32_t r) { return ids[r].empty() ? ~0u : ids[r].front(); };
    return key(x) < key(y);
  });
  simulate("vertex by vertex (state version 2)", by_vertex);
  simulate("rows by their smallest id", by_smallest);
  simulate("stored: largest bicluster first (version 3)", stored);
}

// Relight time of the default compression under several bicluster numberings (the order of
// the biclusters before pack), C++ and OpenCL, beside the uncompressed CSR product.
TEST(BiclusterMeasure, DISABLED_RelightTiming) {
  tbb::task_arena arena(env_int("BICLUSTER_THREADS", tbb::this_task_arena::max_concurrency()));
  arena.execute([] { relight_timing(); });
}

void relight_timing() {
  const Loaded l = load_scene();
  const TransferMatrix& t = l.st.result.transfer;
  SearchOptions options;
  options.groups = env_int("BICLUSTER_GROUPS", kDefaultGroups);
  options.rows_per_vertex = static_cast<std::size_t>(t.local_count());
  const Biclustering b = search(counts_of(t), options, Progress::null());
  auto lights = evaluation_lights(l.desc.cubemap_resolution, 1);
  if (std::getenv("BICLUSTER_UNIFORM_LIGHT")) {
    // As experiments/lossless_check.cpp: radiance uniform in [0, 1) per pixel and channel.
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<float> uniform(0.f, 1.f);
    for (auto& px : lights[0].radiance.radiance) px = Rgb(uniform(rng), uniform(rng), uniform(rng));
  }
  const auto light_vector = lights[0].radiance.light_vector();
  const auto exact = relight_exact_double(t, light_vector);
  const int reps = env_int("BICLUSTER_REPS", 21);
  ClContext* ctx = default_context();
  {
    std::vector<double> ms;
    LocalRadiance out = relight_exact(t, light_vector);
    std::vector<Rgb> o(t.rows());
    for (int i = 0; i < reps; ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      relight_exact(t, light_vector, o);
      ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    std::printf("uncompressed C++ %.3f ms\n", median(ms));
  }
  auto run = [&](const char* name, const Biclustering& order) {
    const BiclusterTransfer ct(pack(order, t));
    const LightCoeffs coeffs = ct.project_light(lights[0].radiance);
    LocalRadiance out;
    std::vector<double> ms;
    for (int i = 0; i < reps; ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      ct.relight(coeffs, out);
      ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    double d2 = 0, n2 = 0, largest = 0, worst = 0;
    for (std::size_t j = 0; j < out.values.size(); ++j)
      for (int c = 0; c < 3; ++c) {
        d2 += (out.values[j][c] - exact[j][c]) * (out.values[j][c] - exact[j][c]);
        n2 += exact[j][c] * exact[j][c];
        largest = std::max(largest, std::abs(exact[j][c]));
      }
    // Per value, relative to the value floored at 1e-6 of the largest (as the lossless check of
    // experiments/lossless_check.h).
    for (std::size_t j = 0; j < out.values.size(); ++j)
      for (int c = 0; c < 3; ++c)
        worst = std::max(worst, std::abs(out.values[j][c] - exact[j][c]) /
                                    std::max(std::abs(exact[j][c]), 1e-6 * largest));
    std::printf("worst per-value relative error %.2e\n", worst);
    double dev = 0;
    if (ctx) {
      auto device = upload_compressed(ct, *ctx);
      std::vector<double> kms;
      for (int i = 0; i < reps; ++i) kms.push_back(device->relight_on_device(coeffs));
      dev = median(kms);
    }
    std::printf("%-14s C++ %.3f ms (rel. L2 %.2e), OpenCL %.3f ms\n", name, median(ms),
                std::sqrt(d2 / n2), dev);
    std::fflush(stdout);
  };
  run("search order", b);
}

}  // namespace
}  // namespace prt::bicluster
