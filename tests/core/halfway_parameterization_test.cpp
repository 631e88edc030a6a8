// The halfway/difference parameterisation (btf/halfway_parameterization.h): GSHD's map from
// (halfway, difference) back to (in, out) inverts the halfway vector; the halfway weights are
// btf_view_samples on the half grid, rows of 1; the GSHD resampling reproduces a function that
// is constant where the resampling is valid.
#include "prtlab/btf/halfway_parameterization.h"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <map>
#include <random>

#include "support/random_directions.h"

namespace prt {
namespace {

TEST(HalfwayParameterization, GshdInvertsTheHalfwayVector) {
  std::mt19937_64 rng(4);
  for (int i = 0; i < 200; ++i) {
    Vec3d h = testing::random_direction(rng), d = testing::random_direction(rng);
    h.z = std::abs(h.z) + 1e-3;
    d.z = std::abs(d.z) + 1e-3;
    h = glm::normalize(h);
    d = glm::normalize(d);
    const auto [in, out] = gshd_to_in_out(h, d);
    EXPECT_NEAR(glm::length(in), 1.0, 1e-12);
    EXPECT_NEAR(glm::length(out), 1.0, 1e-12);
    const Vec3d back = glm::normalize(in + out);
    EXPECT_NEAR(glm::length(back - h), 0.0, 1e-9);
    EXPECT_NEAR(glm::dot(in, h), d.z, 1e-12);  // the difference's polar angle is theta_d
  }
}

TEST(HalfwayParameterization, HalfwayWeightsAreTheHalfGridInterpolation) {
  const auto w = halfway_weights(4, 3, 5);
  ASSERT_EQ(w.rows(), 16 * 9);
  ASSERT_EQ(w.cols(), 25);
  const auto lights = light_directions_f(4), views = light_directions_f(3);
  for (int s = 0; s < w.rows(); ++s) {
    double sum = 0;
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator i(w, s); i; ++i)
      sum += i.value();
    EXPECT_NEAR(sum, 1.0, 1e-6);
    const BtfViewSamples expect =
        btf_view_samples(5, glm::normalize(lights[s % 16] + clamp_to_hemisphere(views[s / 16])));
    std::map<int, double> want;  // corners may repeat at the grid's edge: their weights add
    for (int k = 0; k < 4; ++k)
      if (expect.weight[k] != 0.0f) want[expect.view[k]] += expect.weight[k];
    for (const auto& [cell, weight] : want) EXPECT_NEAR(w.coeff(s, cell), weight, 1e-7);
    EXPECT_EQ(static_cast<std::size_t>(w.row(s).nonZeros()), want.size());
  }
}

TEST(HalfwayParameterization, ResamplingKeepsAConstantAndMarksBelowHorizonPairs) {
  const GshdResampling g = gshd_resampling(5, 4, 6, 6);
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(25 * 16);
  const Eigen::VectorXd hd = g.weights * ones;
  int valid = 0, invalid = 0;
  for (Eigen::Index row = 0; row < hd.size(); ++row) {
    if (g.valid[static_cast<std::size_t>(row)]) {
      ++valid;
      EXPECT_NEAR(hd[row], 1.0, 1e-6);
    } else {
      ++invalid;
      EXPECT_EQ(hd[row], 0.0);
    }
  }
  EXPECT_GT(valid, 0);
  EXPECT_GT(invalid, 0) << "grazing halfway directions with wide differences leave the hemisphere";
}

}  // namespace
}  // namespace prt
