// Regularised least-squares projection onto SRBFs: a function in the SRBFs' span is recovered
// within the pixel quadrature's error, the sparse projection equals the dense one, the Gram matrix
// is the quadrature of the kernels' products, and the ridge bounds the condition number.
#include "prtlab/sphere/srbf_projection.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <random>

#include "prtlab/base/error.h"
#include "prtlab/sphere/icosphere.h"

namespace prt {
namespace {

SrbfBasis icosphere_basis(int level, double lambda) {
  SrbfBasis b;
  b.centres = icosphere_vertices(level);
  b.bandwidths.assign(b.centres.size(), lambda);
  return b;
}

TEST(SrbfProjection, RecoversAFunctionInTheSpanAndSparseEqualsDense) {
  const CubemapLayout layout(32);
  const SrbfBasis basis = icosphere_basis(1, 8.0);  // 42 wide Gaussians
  const SrbfProjector p(basis, layout, 0.0);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd a(42);
  for (auto& v : a) v = u(rng);
  std::vector<double> f(static_cast<std::size_t>(layout.pixel_count()));
  for (int k = 0; k < layout.pixel_count(); ++k) {
    double s = 0;
    for (int j = 0; j < 42; ++j)
      s += a[j] * srbf_eval(basis.kernel, glm::dot(layout.direction(k), basis.centres[j]), 8.0);
    f[static_cast<std::size_t>(k)] = s;
  }
  const Eigen::VectorXd c = p.project(f);
  // b is the pixel midpoint rule of integral f G_j = (A a)_j; its error e = W^T f - A a reaches
  // the coefficients through A^-1: |c - a| <= |e| / lambda_min(A).
  const Eigen::MatrixXd gram = srbf_inner_products(basis, basis);
  const Eigen::Map<const Eigen::VectorXd> fv(f.data(), static_cast<Eigen::Index>(f.size()));
  const double e = (p.pixel_weights().transpose() * fv - gram * a).norm();
  const double lambda_min =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(gram).eigenvalues().minCoeff();
  EXPECT_LE((c - a).norm(), e / lambda_min * (1 + 1e-6) + 1e-12);
  EXPECT_LT((c - a).norm(), 1e-2 * a.norm());
  RecordProperty("coefficient_error", std::to_string((c - a).norm() / a.norm()));
  // A row of T: sparse pixels.
  std::vector<std::uint32_t> pix = {3, 100, 777, 4000, 6000};
  std::vector<double> val = {0.25, 1.0, 0.5, 0.75, 1.0};
  std::vector<double> dense(static_cast<std::size_t>(layout.pixel_count()), 0.0);
  for (std::size_t i = 0; i < pix.size(); ++i) dense[pix[i]] = val[i];
  EXPECT_LT((p.project_sparse(pix, val) - p.project(dense)).norm(),
            1e-12 * p.project(dense).norm() + 1e-15);
}

TEST(SrbfProjection, GramIsTheQuadratureOfTheProductsAndTheRidgeBoundsTheConditioning) {
  const CubemapLayout layout(64);
  const SrbfBasis basis = icosphere_basis(2, 162.1);  // 162 centres at the paper's bandwidth
  const Eigen::MatrixXd a = srbf_inner_products(basis, basis);
  // The pixel quadrature of G_i G_j: sum_k G_i(d_k) G_j(d_k) Omega_k.
  const SrbfProjector p(basis, layout, 1e-6);
  Eigen::MatrixXd q = Eigen::MatrixXd::Zero(162, 162);
  for (int k = 0; k < layout.pixel_count(); ++k) {
    const Eigen::RowVectorXd w = p.pixel_weights().row(k);
    q += w.transpose() * (w / layout.solid_angle(k));
  }
  EXPECT_LT((q - a).cwiseAbs().maxCoeff(), 2e-3 * a.diagonal().maxCoeff());
  EXPECT_GT(p.gram_condition_number(), 1.0);
  EXPECT_LE(p.condition_number(), p.gram_condition_number() * (1 + 1e-9));
  EXPECT_LE(p.condition_number(), 1.0 + 1.0 / 1e-6 + 1e-3);
  // The interpolation matrix of eq. 13 between two different sets, same closed form.
  const SrbfBasis light = icosphere_basis(1, 20.0);
  const Eigen::MatrixXd x = srbf_inner_products(basis, light);
  EXPECT_EQ(x.rows(), 162);
  EXPECT_EQ(x.cols(), 42);
  EXPECT_DOUBLE_EQ(x(5, 7), srbf_convolution(SrbfKernel::kGaussian, basis.centres[5], 162.1,
                                             light.centres[7], 20.0));
}

TEST(SrbfProjection, BadInputsAreErrors) {
  const CubemapLayout layout(8);
  SrbfBasis empty;
  EXPECT_THROW(SrbfProjector(empty, layout, 0.0), ParameterError);
  const SrbfBasis b = icosphere_basis(0, 5.0);
  EXPECT_THROW(SrbfProjector(b, layout, -1.0), ParameterError);
  const SrbfProjector p(b, layout, 0.0);
  EXPECT_THROW(p.project(std::vector<double>(3)), ParameterError);
  const std::uint32_t bad[] = {100000};
  const double one[] = {1.0};
  EXPECT_THROW(p.project_sparse(bad, one), ParameterError);
}

}  // namespace
}  // namespace prt
