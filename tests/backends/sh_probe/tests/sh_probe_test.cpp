// The SH-output test backend: its output is SH, the bins see the projection of L* onto the SH
// cell integrals, and with as many coefficients as cells (order^2 = M, B invertible) nothing
// is lost.
#include "sh_probe/sh_probe.h"

#include <gtest/gtest.h>

#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/transfer_error.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/transfer/radiance_to_bins.h"
#include "prtlab/transfer/random_transfer.h"

namespace prt {
namespace {

std::unique_ptr<CompressedTransfer> compress(const TransferMatrix& t, int side, int res,
                                             int order) {
  const CubemapLayout cubemap(res);
  const HemisphereGrid grid(side);
  return CompressorRegistry::instance()
      .create("sh_probe", {{"order", std::to_string(order)}})
      ->compress({t, nullptr, cubemap, grid}, Progress::null());
}

TEST(ShProbe, WithOrderSquaredEqualToMItIsLossless) {
  const TransferMatrix t = random_transfer(2, RandomTransferSpec{.vertices = 6,
                                                                 .grid_side = 3,
                                                                 .resolution = 3,
                                                                 .supersampling = 2,
                                                                 .density = 0.5,
                                                                 .empty_vertices = {}});
  const auto ct = compress(t, 3, 3, 3);  // 9 coefficients, 9 cells
  EXPECT_EQ(ct->output_basis(), RadianceBasis::kSphericalHarmonics);
  EXPECT_LT(*ct->expected_frobenius_error(), 1e-5);
  EXPECT_LT(frobenius_error(*ct, t, HemisphereGrid(3)).relative, 1e-4);
}

TEST(ShProbe, FewerCoefficientsLoseWhatItDeclares) {
  const TransferMatrix t = random_transfer(3, RandomTransferSpec{.vertices = 6,
                                                                 .grid_side = 4,
                                                                 .resolution = 3,
                                                                 .supersampling = 2,
                                                                 .density = 0.5,
                                                                 .empty_vertices = {}});
  const auto ct = compress(t, 4, 3, 2);  // 4 coefficients, 16 cells
  const double expected = *ct->expected_frobenius_error();
  EXPECT_GT(expected, 0.1);
  const FrobeniusError measured = frobenius_error(*ct, t, HemisphereGrid(4));
  EXPECT_NEAR(measured.relative, expected, 1e-4 * expected);
}

}  // namespace
}  // namespace prt
