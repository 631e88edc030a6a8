// Backend `bicluster`, lossy mode (compressors/bicluster/bicluster_budget.h): the per-column L1
// budget bounds the relative L1 error of every non-negative light, E = 0 is the lossless result
// bit for bit, the drop sets are nested so the cost never rises with E, and the backend declares
// (and saves) the bound in relative L1.
#include "bicluster/bicluster_budget.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>
#include <tuple>

#include "bicluster/bicluster.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/transfer/random_transfer.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt::bicluster {
namespace {

// A random sparse non-negative count matrix with few distinct values (so that biclusters of
// several columns form) and a share of 1x1-only entries.
SparseCounts random_counts(std::mt19937_64& rng, std::size_t rows, std::size_t cols, double density,
                           int values) {
  SparseCounts s;
  s.rows = rows;
  s.cols = cols;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (std::size_t j = 0; j < rows; ++j) {
    for (std::size_t k = 0; k < cols; ++k) {
      if (u(rng) >= density) continue;
      s.columns.push_back(static_cast<std::uint32_t>(k));
      s.values.push_back(1 + static_cast<std::int32_t>(rng() % static_cast<unsigned>(values)));
    }
    s.offsets.push_back(static_cast<std::uint32_t>(s.values.size()));
  }
  return s;
}

// y = A x for a CSR of counts, in double.
std::vector<double> product(const SparseCounts& a, const std::vector<double>& x) {
  std::vector<double> y(a.rows, 0.0);
  for (std::size_t j = 0; j < a.rows; ++j)
    for (std::uint32_t i = a.offsets[j]; i < a.offsets[j + 1]; ++i)
      y[j] += a.values[i] * x[a.columns[i]];
  return y;
}

double relative_l1(const std::vector<double>& a, const std::vector<double>& ref) {
  double diff = 0, norm = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    diff += std::abs(a[i] - ref[i]);
    norm += std::abs(ref[i]);
  }
  return diff / norm;
}

// A non-negative light: some pixels dark, a few very bright (all-frequency), the rest uniform.
std::vector<double> random_light(std::mt19937_64& rng, std::size_t n) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> x(n);
  for (double& v : x) {
    const double p = u(rng);
    v = p < 0.3 ? 0.0 : p < 0.35 ? 100.0 * u(rng) : u(rng);
  }
  return x;
}

TEST(BiclusterBudget, RelativeL1ErrorOfAnyNonNegativeLightStaysWithinE) {
  std::mt19937_64 rng(21);
  const double levels[] = {0.001, 0.01, 0.05, 0.2, 0.6, 1.0};
  int dropped_somewhere = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const SparseCounts t = random_counts(rng, 40 + rng() % 60, 20 + rng() % 40,
                                         0.15 + 0.1 * (trial % 4), 1 + static_cast<int>(rng() % 4));
    const Biclustering lossless = search(t, static_cast<std::uint64_t>(trial), Progress::null());
    const auto mass = column_mass(t);
    for (double e : levels) {
      SCOPED_TRACE(::testing::Message() << "trial " << trial << " E " << e);
      Biclustering b = lossless;
      const BudgetResult r = drop_within_budget(b, mass, e);
      EXPECT_LE(r.bound, e);
      dropped_somewhere += r.dropped_biclusters + r.dropped_terms > 0;
      const SparseCounts approx = b.reconstruct();
      for (int l = 0; l < 8; ++l) {
        const auto x = random_light(rng, t.cols);
        const auto exact = product(t, x);
        const auto got = product(approx, x);
        EXPECT_LE(relative_l1(got, exact), r.bound * (1 + 1e-12) + 1e-15) << "light " << l;
      }
      // A light on one column alone: the bound holds column by column (|T - T~| summed down a
      // column is at most the dropped mass, E times the column's mass at most).
      for (std::size_t k = 0; k < t.cols; ++k) {
        if (mass[k] == 0) continue;
        std::vector<double> x(t.cols, 0.0);
        x[k] = 1.0;
        EXPECT_LE(relative_l1(product(approx, x), product(t, x)), e * (1 + 1e-12))
            << "column " << k;
      }
    }
  }
  EXPECT_GT(dropped_somewhere, 20) << "the budgets should drop items in most cases";
}

// The items a result keeps, comparable across budgets: each bicluster as itself, each residual
// term by position and value.
struct KeptItems {
  std::vector<Bicluster> biclusters;
  std::vector<std::tuple<std::uint32_t, std::uint32_t, std::int64_t>> terms;
};
KeptItems kept_items(const Biclustering& b) {
  KeptItems k;
  k.biclusters = b.biclusters;
  std::sort(k.biclusters.begin(), k.biclusters.end(), [](const Bicluster& x, const Bicluster& y) {
    return std::tie(x.rows, x.cols, x.constants) < std::tie(y.rows, y.cols, y.constants);
  });
  for (const Term& t : b.residual) k.terms.emplace_back(t.row, t.col, t.value);
  std::sort(k.terms.begin(), k.terms.end());
  return k;
}
// Every item of `larger_budget` is also in `smaller_budget` (both sorted).
bool nested(const KeptItems& larger_budget, const KeptItems& smaller_budget) {
  auto less = [](const Bicluster& x, const Bicluster& y) {
    return std::tie(x.rows, x.cols, x.constants) < std::tie(y.rows, y.cols, y.constants);
  };
  return std::includes(smaller_budget.biclusters.begin(), smaller_budget.biclusters.end(),
                       larger_budget.biclusters.begin(), larger_budget.biclusters.end(), less) &&
         std::includes(smaller_budget.terms.begin(), smaller_budget.terms.end(),
                       larger_budget.terms.begin(), larger_budget.terms.end());
}

TEST(BiclusterBudget, CostIsNonIncreasingInEAndDropSetsAreNested) {
  std::mt19937_64 rng(33);
  for (int trial = 0; trial < 10; ++trial) {
    const SparseCounts t = random_counts(rng, 80, 40, 0.3, 1 + trial % 3);
    const Biclustering lossless = search(t, 5, Progress::null());
    const auto mass = column_mass(t);
    std::int64_t previous_cost = lossless.cost();
    Biclustering consolidated = lossless;
    consolidate_residual(consolidated);
    KeptItems previous = kept_items(consolidated);
    for (double e = 0.0; e <= 1.0; e += 0.05) {
      Biclustering b = lossless;
      const BudgetResult r = drop_within_budget(b, mass, e);
      EXPECT_LE(b.cost(), previous_cost) << "trial " << trial << " E " << e;
      EXPECT_EQ(b.cost() + r.flops_saved, consolidated.cost());
      // Nested: what is dropped at a smaller E is dropped at E too, i.e. every item kept at E
      // was kept at the smaller E.
      const KeptItems items = kept_items(b);
      EXPECT_TRUE(nested(items, previous))
          << "trial " << trial << " E " << e << ": an item dropped at a smaller budget came back";
      previous_cost = b.cost();
      previous = items;
    }
    EXPECT_LT(previous_cost, consolidated.cost()) << "E near 1 drops something";
  }
}

TEST(BiclusterBudget, ZeroBudgetDropsNothing) {
  std::mt19937_64 rng(3);
  const SparseCounts t = random_counts(rng, 60, 30, 0.4, 3);
  Biclustering b = search(t, 1, Progress::null());
  Biclustering c = b;
  consolidate_residual(c);
  const BudgetResult r = drop_within_budget(b, column_mass(t), 0.0);
  EXPECT_EQ(r.dropped_biclusters + r.dropped_terms, 0u);
  EXPECT_EQ(r.bound, 0.0);
  EXPECT_EQ(b, c);
  EXPECT_EQ(b.reconstruct(), t);
}

// ---- through the backend ----

std::unique_ptr<CompressedTransfer> compress(const TransferMatrix& t, const std::string& error,
                                             int resolution, int side) {
  const CubemapLayout cubemap(resolution);
  const HemisphereGrid grid(side);
  return CompressorRegistry::instance()
      .create("bicluster", {{"seed", "4"}, {"groups", "3"}, {"error", error}})
      ->compress({t, nullptr, cubemap, grid}, Progress::null());
}

LightCoeffs random_pixel_light(std::mt19937_64& rng, std::size_t n) {
  LightCoeffs light{"pixel", std::vector<Rgb>(n)};
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (Rgb& v : light.values) {
    const float p = u(rng);
    v = p < 0.3f    ? Rgb(0.f)
        : p < 0.35f ? Rgb(50.f * u(rng), 20.f * u(rng), 80.f * u(rng))
                    : Rgb(u(rng), u(rng), u(rng));
  }
  return light;
}

double relative_l1_rgb(const LocalRadiance& a, const std::vector<Vec3d>& ref) {
  double diff = 0, norm = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      diff += std::abs(static_cast<double>(a.values[i][c]) - ref[i][c]);
      norm += std::abs(ref[i][c]);
    }
  }
  return diff / norm;
}

TEST(BiclusterBudget, BackendDeclaresARelativeL1BoundThatHoldsAndSurvivesSaveLoad) {
  const TransferMatrix t = random_transfer(8, RandomTransferSpec{60, 3, 3, 2, 0.5, {}});
  const auto lossless = compress(t, "0", 3, 3);
  EXPECT_EQ(lossless->declared_error_bound(), 0.0);
  EXPECT_EQ(lossless->declared_error_norm(), CompressedTransfer::ErrorNorm::kRelativeL1);
  std::mt19937_64 rng(12);
  double previous_flops = lossless->flops_per_relight();
  for (const char* e : {"0.02", "0.1", "0.4"}) {
    SCOPED_TRACE(std::string("error ") + e);
    const auto ct = compress(t, e, 3, 3);
    const double bound = ct->declared_error_bound();
    EXPECT_GT(bound, 0.0);
    EXPECT_LE(bound, std::stod(e));
    EXPECT_LE(ct->flops_per_relight(), previous_flops);
    previous_flops = ct->flops_per_relight();
    for (int l = 0; l < 6; ++l) {
      const LightCoeffs light = random_pixel_light(rng, t.cols());
      LocalRadiance out;
      ct->relight(light, out);
      EXPECT_LE(relative_l1_rgb(out, relight_exact_double(t, light.values)), bound * (1 + 1e-6))
          << "light " << l;
    }
    const auto path = std::filesystem::temp_directory_path() /
                      ("bicluster_budget_" + std::to_string(::getpid()) + ".prt");
    save_compressed(*ct, path);
    const auto loaded = load_compressed(path);
    std::filesystem::remove(path);
    EXPECT_EQ(loaded->declared_error_bound(), bound);
    EXPECT_EQ(loaded->flops_per_relight(), ct->flops_per_relight());
    EXPECT_EQ(dynamic_cast<const BiclusterTransfer&>(*loaded).arrays().error, std::stod(e));
  }
  EXPECT_LT(previous_flops, lossless->flops_per_relight());
}

TEST(BiclusterBudget, ErrorZeroIsBitIdenticalToTheLosslessDefault) {
  const TransferMatrix t = random_transfer(5, RandomTransferSpec{40, 3, 3, 2, 0.5, {}});
  const CubemapLayout cubemap(3);
  const HemisphereGrid grid(3);
  const auto by_default = CompressorRegistry::instance()
                              .create("bicluster", {{"seed", "4"}, {"groups", "3"}})
                              ->compress({t, nullptr, cubemap, grid}, Progress::null());
  const auto zero = compress(t, "0", 3, 3);
  const auto& a = dynamic_cast<const BiclusterTransfer&>(*by_default).arrays();
  const auto& b = dynamic_cast<const BiclusterTransfer&>(*zero).arrays();
  EXPECT_EQ(a.bic_col_offsets, b.bic_col_offsets);
  EXPECT_EQ(a.bic_columns, b.bic_columns);
  EXPECT_EQ(a.bic_constants, b.bic_constants);
  EXPECT_EQ(a.slice_offsets, b.slice_offsets);
  EXPECT_EQ(a.slice_rows, b.slice_rows);
  EXPECT_EQ(a.slice_base, b.slice_base);
  EXPECT_EQ(a.slice_codes, b.slice_codes);
  EXPECT_EQ(reconstruct(b), counts_of(t));
  std::mt19937_64 rng(2);
  const LightCoeffs light = random_pixel_light(rng, t.cols());
  LocalRadiance x, y;
  by_default->relight(light, x);
  zero->relight(light, y);
  ASSERT_EQ(x.values.size(), y.values.size());
  EXPECT_EQ(std::memcmp(x.values.data(), y.values.data(), x.values.size() * sizeof(Rgb)), 0);
}

}  // namespace
}  // namespace prt::bicluster
