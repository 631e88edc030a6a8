// The halfway/difference parameterisation (btf/halfway_parameterization.h): GSHD's map from
// (halfway, difference) back to (in, out) inverts the halfway vector; the halfway weights are
// btf_view_samples on the half grid, rows of 1; the GSHD resampling reproduces a function that
// is constant where the resampling is valid, and reads the incident direction on the light grid
// and the exitant one on the view grid: on an ABRDF that is a product of distinct functions of
// the light and the view it gives the interpolated product at each row's pair, close to the
// analytic value, where the same weights applied with the light and view indices swapped give
// a clearly different result (the negative control that makes the test able to fail).
#include "prtlab/btf/halfway_parameterization.h"

#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <map>
#include <random>

#include "prtlab/sphere/hemisphere_grid.h"
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

// g(l) r(e) at the in/out samples, s = view * M + light.
double light_part(const Vec3d& l) {
  return 1.0 + 3.0 * l.x;
}
double view_part(const Vec3d& e) {
  return 2.0 - e.y + 0.5 * e.z;
}

TEST(HalfwayParameterization, ResamplingReadsTheLightOnTheLightGridAndTheViewOnTheViewGrid) {
  // Equal sides, so that swapping the light and view indices is a possible mistake.
  const int side = 6, m = side * side;
  const GshdResampling g = gshd_resampling(side, side, 8, 8);
  const HemisphereGrid grid(side);
  Eigen::VectorXd f(m * m), swapped(m * m);
  for (int v = 0; v < m; ++v)
    for (int j = 0; j < m; ++j) {
      f[v * m + j] = light_part(grid.direction(j)) * view_part(grid.direction(v));
      swapped[j * m + v] = f[v * m + j];  // the same ABRDF with light and view indices swapped
    }
  const Eigen::VectorXd hd = g.weights * f, hd_swapped = g.weights * swapped;
  const HemisphereGrid half(8), diff(8);
  double exact_err = 0, analytic_err = 0, swapped_exact = 0, swapped_analytic = 0;
  int rows = 0;
  for (int a = 0; a < half.cell_count(); ++a)
    for (int b = 0; b < diff.cell_count(); ++b) {
      const int row = a * diff.cell_count() + b;
      if (!g.valid[static_cast<std::size_t>(row)]) continue;
      ++rows;
      const auto [in, out] = gshd_to_in_out(half.direction(a), diff.direction(b));
      // The header's definition: btf_view_samples of the incident direction on the light grid
      // times that of the exitant direction on the view grid.
      const BtfViewSamples li = btf_view_samples(side, Vec3(in)),
                           vo = btf_view_samples(side, Vec3(out));
      double gl = 0, re = 0;
      for (int k = 0; k < 4; ++k) {
        gl += li.weight[k] * light_part(grid.direction(li.view[k]));
        re += vo.weight[k] * view_part(grid.direction(vo.view[k]));
      }
      exact_err = std::max(exact_err, std::abs(hd[row] - gl * re));
      swapped_exact = std::max(swapped_exact, std::abs(hd_swapped[row] - gl * re));
      const double analytic = light_part(in) * view_part(out);
      analytic_err += std::abs(hd[row] - analytic);
      swapped_analytic += std::abs(hd_swapped[row] - analytic);
    }
  ASSERT_GT(rows, 100);
  analytic_err /= rows;
  swapped_analytic /= rows;
  EXPECT_LT(exact_err, 1e-9) << "the resampling is the tensor product of the two interpolations";
  // The interpolation error of a smooth function on a 6 x 6 grid (mostly the clamped
  // extrapolation between the outer sample centres and the horizon) is a per cent or two of
  // its range (|g r| up to 14); the swap moves the light part to the exitant direction, which
  // (measured) costs about 30 times more.
  EXPECT_LT(analytic_err, 0.25) << "mean |resampled - g(in) r(out)|";
  EXPECT_GT(swapped_exact, 2.0) << "negative control: swapped indices must fail the exact check";
  EXPECT_GT(swapped_analytic, 10 * analytic_err)
      << "negative control: swapped indices must fail the analytic check";
}

}  // namespace
}  // namespace prt
