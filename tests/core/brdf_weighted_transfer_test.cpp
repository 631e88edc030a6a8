// The BRDF-weighted transfer: the Cook-Torrance BRDF against its closed form at the normal and
// its reciprocity; the K-term fold against an independent unweighted SVD of the kernel, its
// truncation error equal to the dropped singular values; the folded transfer times the view
// basis against the direct dense BRDF-weighted integral F T_x (exact at K = M, within the
// derived truncation bound below it).
#include "prtlab/transfer/brdf_weighted_transfer.h"

#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cmath>
#include <numbers>
#include <random>

#include "prtlab/base/error.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/transfer/random_transfer.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt {
namespace {

Vec3d random_upper(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  for (;;) {
    Vec3d d(n(rng), n(rng), std::abs(n(rng)));
    const double l = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    if (l > 1e-3 && d.z / l > 1e-3) return d / l;
  }
}

TEST(CookTorrance, ClosedFormAtTheNormalAndReciprocity) {
  const CookTorrance ct{0.25, 0.4, 0.6};
  const Vec3d n(0, 0, 1);
  // D(n) = 1 / (pi m^2), F = F0, G = 1, cosines 1.
  const double expected =
      0.25 / std::numbers::pi + 0.75 * 0.6 / (4.0 * std::numbers::pi * 0.4 * 0.4);
  EXPECT_NEAR(ct(n, n), expected, 1e-12);
  std::mt19937_64 rng(5);
  for (int i = 0; i < 200; ++i) {
    const Vec3d l = random_upper(rng), v = random_upper(rng);
    EXPECT_NEAR(ct(l, v), ct(v, l), 1e-12 * (1 + ct(l, v)));
    EXPECT_GE(ct(l, v), 0.25 / std::numbers::pi - 1e-15);
  }
  EXPECT_EQ(ct(Vec3d(0, 0, -1), n), 0.0);
  EXPECT_THROW((CookTorrance{1.5, 0.3, 0.5}.validate()), ParameterError);
  EXPECT_THROW((CookTorrance{0.3, 0.0, 0.5}.validate()), ParameterError);
  EXPECT_THROW((CookTorrance{0.3, 0.3, -0.1}.validate()), ParameterError);
}

TEST(BrdfFold, TruncationErrorIsTheDroppedSingularValues) {
  const HemisphereGrid grid(6);
  const CookTorrance ct;
  const Eigen::MatrixXd f = brdf_cosine_kernel(grid, ct);
  // Independent: the unweighted SVD of F (the weights are one constant on an equal-area grid).
  const Eigen::BDCSVD<Eigen::MatrixXd> svd(f, Eigen::ComputeThinU | Eigen::ComputeThinV);
  for (int k : {1, 4, 16, 36}) {
    const BrdfFold fold = fold_brdf(grid, ct, k);
    ASSERT_EQ(fold.view.rows(), 36);
    ASSERT_EQ(fold.view.cols(), k);
    ASSERT_EQ(fold.light.rows(), k);
    const Eigen::MatrixXd fk = svd.matrixU().leftCols(k) *
                               svd.singularValues().head(k).asDiagonal() *
                               svd.matrixV().leftCols(k).transpose();
    EXPECT_LT((fold.view * fold.light - fk).norm(), 1e-10 * f.norm()) << k;
    const double w = std::sqrt(fold.view_weight * fold.light_weight);
    const double dropped = fold.singular_values.tail(36 - k).squaredNorm();
    const double err = (w * (f - fold.view * fold.light)).squaredNorm();
    EXPECT_NEAR(err, dropped, 1e-10 * fold.singular_values.squaredNorm()) << k;
    EXPECT_NEAR(fold.dropped_fraction(), dropped / fold.singular_values.squaredNorm(), 1e-12);
    // Phi's columns are orthonormal under the view-cell weight.
    const Eigen::MatrixXd gram = fold.view.transpose() * fold.view * fold.view_weight;
    EXPECT_LT((gram - Eigen::MatrixXd::Identity(k, k)).norm(), 1e-10) << k;
  }
  EXPECT_EQ(fold_brdf(grid, ct, 36).dropped_fraction(), 0.0);
  EXPECT_THROW(fold_brdf(grid, ct, 0), ParameterError);
  EXPECT_THROW(fold_brdf(grid, ct, 37), ParameterError);
}

TEST(BrdfFold, FoldedTransferEqualsTheDirectWeightedIntegralUpToTheTruncation) {
  RandomTransferSpec spec;
  spec.vertices = 12;
  spec.grid_side = 4;
  spec.resolution = 6;
  spec.density = 0.6;
  const TransferMatrix t = random_transfer(11, spec);
  const HemisphereGrid grid(4);
  const CookTorrance ct{0.2, 0.25, 0.7};
  const Eigen::MatrixXd f = brdf_cosine_kernel(grid, ct);
  double folded_sq = 0;
  for (int k : {16, 6, 2}) {
    const BrdfFold fold = fold_brdf(grid, ct, k);
    const double w = std::sqrt(fold.view_weight);
    const double sigma_next = k < 16 ? fold.singular_values(k) : 0.0;
    double worst_gap = 0;
    folded_sq = 0;
    for (std::size_t x = 0; x < t.vertex_count(); ++x) {
      const Eigen::MatrixXd direct = brdf_weighted_vertex(t, f, x);  // M x N
      const Eigen::MatrixXd folded = folded_vertex(t, fold, x);      // K x N
      folded_sq += folded.squaredNorm();
      const Eigen::MatrixXd tx = brdf_weighted_vertex(t, Eigen::MatrixXd::Identity(16, 16), x);
      const double err = (w * (direct - fold.view * folded)).norm();
      // (F - F_K) T_x = [w (F - F_K) w_j] (T_x / w_j): at most sigma_{K+1} ||T_x||_F / w_j.
      const double bound = sigma_next * tx.norm() / std::sqrt(fold.light_weight);
      if (k == 16) {
        EXPECT_LT(err, 1e-10 * (1 + (w * direct).norm())) << x;
      } else {
        EXPECT_LE(err, bound * (1 + 1e-10) + 1e-14) << k << " " << x;
        worst_gap = std::max(worst_gap, err);
      }
    }
    if (k < 16) {
      EXPECT_GT(worst_gap, 0.0) << "a truncation that drops nothing tests nothing";
    }
    EXPECT_NEAR(folded_squared_norm(t, fold), folded_sq, 1e-10 * folded_sq) << k;
  }
  EXPECT_THROW(folded_vertex(t, fold_brdf(HemisphereGrid(3), ct, 2), 0), ParameterError);
  EXPECT_THROW(folded_vertex(t, fold_brdf(grid, ct, 2), t.vertex_count()), ParameterError);
}

}  // namespace
}  // namespace prt
