// The BRDF-weighted signal as a declared input: the folded CSR rows against the dense fold of
// the transfer layer (folded_vertex), their norm against folded_squared_norm (T's entries, a
// different summation), the source's reuse of the rows for one BRDF and its refold for another,
// and the parameters every backend declaring the input receives.
#include "prtlab/compress/brdf_signal.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "prtlab/base/error.h"
#include "prtlab/base/progress.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/sphere/cubemap.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/transfer/random_transfer.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt {
namespace {

// 20 vertices, M = 9 (S = 3), N = 96 (R = 4).
TransferMatrix test_transfer() {
  return random_transfer(3, RandomTransferSpec{20, 3, 4, 4, 0.4, {4}});
}

BrdfSignalParams brdf_params(int terms, double roughness = 0.3) {
  BrdfSignalParams p;
  p.enabled = true;
  p.terms = terms;
  p.brdf.roughness = roughness;
  return p;
}

TEST(BrdfSignal, FoldedRowsAreTheDenseFoldOfEveryVertex) {
  const TransferMatrix t = test_transfer();
  const HemisphereGrid grid(3);
  for (int terms : {1, 4, 9}) {
    SCOPED_TRACE(terms);
    const FoldedRows f = fold_transfer_rows(t, grid, brdf_params(terms), Progress::null());
    ASSERT_EQ(f.rows(), t.vertex_count() * static_cast<std::size_t>(terms));
    const Eigen::MatrixXd rows = f.row_set().to_dense();
    double worst = 0;
    for (std::size_t x = 0; x < t.vertex_count(); ++x) {
      const Eigen::MatrixXd want = folded_vertex(t, f.fold, x);
      const Eigen::MatrixXd got = rows.middleRows(static_cast<Eigen::Index>(x) * terms, terms);
      worst = std::max(worst, (got - want).cwiseAbs().maxCoeff() / want.cwiseAbs().maxCoeff());
    }
    EXPECT_LT(worst, 1e-6);  // f32 rounding of double sums
    EXPECT_NEAR(f.squared_norm, folded_squared_norm(t, f.fold), 1e-6 * f.squared_norm);
    // Every stored pixel is one of T_x's: no row is denser than its vertex block.
    std::size_t stored = 0;
    for (std::size_t x = 0; x < t.vertex_count(); ++x) {
      std::vector<std::uint32_t> cols;
      for (std::size_t r = x * 9; r < x * 9 + 9; ++r)
        for (std::uint32_t e = t.row_offsets()[r]; e < t.row_offsets()[r + 1]; ++e)
          cols.push_back(t.column(e));
      std::sort(cols.begin(), cols.end());
      stored += static_cast<std::size_t>(std::unique(cols.begin(), cols.end()) - cols.begin());
    }
    EXPECT_EQ(f.values.size(), stored * static_cast<std::size_t>(terms));
  }
}

TEST(BrdfSignal, SourceFoldsOncePerBrdf) {
  const TransferMatrix t = test_transfer();
  const HemisphereGrid grid(3);
  BrdfSignalSource source;
  const auto a = source.rows(t, grid, brdf_params(4), Progress::null());
  const auto b = source.rows(t, grid, brdf_params(4), Progress::null());
  EXPECT_EQ(a.get(), b.get());
  const auto c = source.rows(t, grid, brdf_params(4, 0.6), Progress::null());
  EXPECT_NE(c.get(), a.get());
  EXPECT_NE(c->values, a->values);
  // Held rows outlive the source's move to another BRDF.
  EXPECT_EQ(a->rows(), 80u);
  const CubemapLayout cubemap(4);
  const TransferInput input{t, nullptr, cubemap, grid, nullptr, {}, &source};
  EXPECT_EQ(brdf_signal_rows(input, brdf_params(4, 0.6), Progress::null()).get(), c.get());
  EXPECT_THROW(fold_transfer_rows(t, HemisphereGrid(2), brdf_params(4), Progress::null()),
               ParameterError);
  EXPECT_THROW(fold_transfer_rows(t, grid, brdf_params(10), Progress::null()), ParameterError);
}

TEST(BrdfSignal, DeclaringBackendsGetTheSameParameters) {
  const auto& registry = CompressorRegistry::instance();
  int declaring = 0;
  for (const auto& name : registry.names()) {
    const CompressorEntry& e = registry.get(name);
    if (!e.inputs.brdf_signal) continue;
    ++declaring;
    for (const ParamSpec& spec : brdf_signal_param_specs()) {
      const auto it = std::find_if(e.params.begin(), e.params.end(),
                                   [&](const ParamSpec& p) { return p.key == spec.key; });
      ASSERT_NE(it, e.params.end()) << name << " lacks " << spec.key;
      EXPECT_EQ(it->default_value, spec.default_value) << name << ": " << spec.key;
      EXPECT_EQ(it->doc, spec.doc) << name << ": " << spec.key;
    }
  }
  EXPECT_GE(declaring, 2) << "cpca and srbf_cta declare the signal";
  const ParamSet ps("test", brdf_signal_param_specs(),
                    {{"signal", "brdf"}, {"brdf_terms", "5"}, {"brdf_fresnel0", "0.9"}},
                    ParamSet::Shared::kExclude);
  const BrdfSignalParams p = brdf_signal_params(ps);
  EXPECT_TRUE(p.enabled);
  EXPECT_EQ(p.terms, 5);
  EXPECT_EQ(p.brdf.fresnel0, 0.9);
  EXPECT_NE(p.key(), brdf_params(5).key());
}

}  // namespace
}  // namespace prt
