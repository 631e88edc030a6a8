// The measured Frobenius and per-vertex errors against independent computations: a
// compressed transfer that is the exact product of another matrix T' has
// ||T' - T||_F computable entry by entry from the two CSR matrices.
#include "prtlab/compress/transfer_error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "prtlab/compress/compressor_registry.h"
#include "prtlab/transfer/random_transfer.h"

namespace prt {
namespace {

std::unique_ptr<CompressedTransfer> exact_of(const TransferMatrix& t, const CubemapLayout& c,
                                             const HemisphereGrid& g) {
  return CompressorRegistry::instance()
      .create("uncompressed", {})
      ->compress({t, nullptr, c, g}, Progress::null());
}

// ||A - B||_F^2 from the CSR entries (dense over each row's union of columns).
double frobenius_sq(const TransferMatrix& a, const TransferMatrix& b) {
  double s = 0;
  for (std::size_t r = 0; r < a.rows(); ++r) {
    std::map<std::uint32_t, double> row;
    for (auto i = a.row_offsets()[r]; i < a.row_offsets()[r + 1]; ++i)
      row[a.column(i)] += a.value(i);
    for (auto i = b.row_offsets()[r]; i < b.row_offsets()[r + 1]; ++i)
      row[b.column(i)] -= b.value(i);
    for (const auto& [k, v] : row) s += v * v;
  }
  return s;
}

TEST(FrobeniusError, ExactAndEstimatedMatchTheEntrywiseNorm) {
  const RandomTransferSpec spec{.vertices = 12,
                                .grid_side = 3,
                                .resolution = 4,
                                .supersampling = 2,
                                .density = 0.5,
                                .empty_vertices = {}};
  const TransferMatrix t = random_transfer(3, spec);
  const TransferMatrix other = random_transfer(4, spec);  // same shape, other entries
  const CubemapLayout cubemap(spec.resolution);
  const HemisphereGrid grid(spec.grid_side);
  double norm_sq = 0;
  for (std::size_t i = 0; i < t.nnz(); ++i) norm_sq += double(t.value(i)) * t.value(i);
  const double expected = std::sqrt(frobenius_sq(other, t) / norm_sq);
  const auto ct = exact_of(other, cubemap, grid);

  const FrobeniusError exact = frobenius_error(*ct, t, grid);
  EXPECT_TRUE(exact.exact);
  EXPECT_EQ(exact.relights, static_cast<int>((t.cols() + 2) / 3));
  EXPECT_NEAR(exact.relative, expected, 1e-5 * expected);

  const FrobeniusError estimate = frobenius_error(*ct, t, grid, 0, 200, 9);
  EXPECT_FALSE(estimate.exact);
  EXPECT_GT(estimate.standard_error, 0.0);
  EXPECT_NEAR(estimate.relative, expected, 5 * estimate.standard_error)
      << "estimate " << estimate.relative << " +- " << estimate.standard_error;

  // The exact transfer itself: 0 up to float rounding.
  EXPECT_LT(frobenius_error(*exact_of(t, cubemap, grid), t, grid).relative, 1e-6);
}

TEST(MaxVertexError, FindsTheOneVertexThatDiffers) {
  const HemisphereGrid grid(2);
  LocalRadiance exact(RadianceBasis::kPixel, 4, 3), approx(RadianceBasis::kPixel, 4, 3);
  for (std::size_t i = 0; i < exact.values.size(); ++i)
    exact.values[i] = approx.values[i] = Rgb(1.f);
  approx.values[2 * 4 + 1] = Rgb(1.f, 1.f, 3.f);  // vertex 2: one bin, one channel off by 2
  const VertexError v = max_vertex_error(approx, exact, grid);
  EXPECT_EQ(v.worst_vertex, 2u);
  EXPECT_NEAR(v.max_relative, 2.0 / std::sqrt(12.0), 1e-6);  // ||(0,..,2)|| / ||ones(12)||
}

}  // namespace
}  // namespace prt
