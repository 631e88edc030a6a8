// SH local radiance evaluated at the bins: the cell integrals of the SH basis against closed
// forms and a finer quadrature, and to_pixel_basis against a direct integration of an SH
// expansion over each cell.
#include "prtlab/transfer/radiance_to_bins.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "prtlab/base/error.h"
#include "prtlab/sphere/spherical_harmonics.h"

namespace prt {
namespace {

TEST(ShCellIntegrals, SumOverTheHemisphereMatchesClosedForms) {
  const HemisphereGrid grid(6);
  const int order = 3, n = sh_count(order);
  const auto b = sh_cell_integrals(grid, order);
  std::vector<double> total(static_cast<std::size_t>(n), 0.0);
  for (int j = 0; j < grid.cell_count(); ++j)
    for (int i = 0; i < n; ++i)
      total[static_cast<std::size_t>(i)] += b[static_cast<std::size_t>(j * n + i)];
  // y_0 is constant 1 / (2 sqrt(pi)): its hemisphere integral is sqrt(pi), whatever the rule.
  EXPECT_NEAR(total[0], std::sqrt(std::numbers::pi), 1e-12);
  // y_2 = sqrt(3 / 4pi) z integrates to sqrt(3 / 4pi) pi. The midpoint rule on sub-squares of
  // side h = 1 / (S q) errs by O(h^2) (z = 1 - max(u^2, v^2) has curvature 2 in the square):
  // 1 / 96^2 ~ 1.1e-4 relative, so 5e-4 leaves a factor of four.
  const double z_integral = std::sqrt(3.0 / (4.0 * std::numbers::pi)) * std::numbers::pi;
  EXPECT_NEAR(total[static_cast<std::size_t>(sh_index(1, 0))], z_integral, 5e-4 * z_integral);
  // Odd in x or y: y_1 (~ y) and y_3 (~ x) vanish over the symmetric hemisphere.
  EXPECT_NEAR(total[static_cast<std::size_t>(sh_index(1, -1))], 0.0, 1e-12);
  EXPECT_NEAR(total[static_cast<std::size_t>(sh_index(1, 1))], 0.0, 1e-12);
}

TEST(ShCellIntegrals, ConvergeUnderRefinement) {
  const HemisphereGrid grid(4);
  const int order = 4, n = sh_count(order);
  const auto coarse = sh_cell_integrals(grid, order, 16);
  const auto fine = sh_cell_integrals(grid, order, 128);
  const double cell = grid.cell_solid_angle();
  double worst = 0;
  for (std::size_t i = 0; i < coarse.size(); ++i)
    worst = std::max(worst, std::abs(coarse[i] - fine[i]) / cell);
  // |y| <= sqrt((2l+1)/4pi) < 0.8 for l < 4; the midpoint rule at q = 16 is far inside 1e-3.
  EXPECT_LT(worst, 1e-3) << "per-cell mean of y_i differs by " << worst;
  EXPECT_EQ(coarse.size(), static_cast<std::size_t>(grid.cell_count() * n));
  EXPECT_THROW(sh_cell_integrals(grid, 11), ParameterError);
}

TEST(ToPixelBasis, IntegratesAnShExpansionOverEachCell) {
  const HemisphereGrid grid(5);
  const int order = 3, n = sh_count(order);
  std::mt19937_64 rng(17);
  std::normal_distribution<float> g;
  LocalRadiance sh(RadianceBasis::kSphericalHarmonics, n, 2);
  for (auto& v : sh.values) v = Rgb(g(rng), g(rng), g(rng));
  const LocalRadiance pixel = to_pixel_basis(sh, grid);
  ASSERT_EQ(pixel.basis, RadianceBasis::kPixel);
  ASSERT_EQ(pixel.dim, grid.cell_count());
  // Independent: integrate f = sum c_i y_i over each cell with a finer midpoint rule.
  const int q = 64, s = grid.side();
  std::vector<double> y(static_cast<std::size_t>(n));
  double worst = 0, largest = 0;
  for (std::size_t p = 0; p < 2; ++p)
    for (int j = 0; j < grid.cell_count(); ++j) {
      Vec3d acc(0.0);
      const int row = j / s, col = j % s;
      for (int v = 0; v < q; ++v)
        for (int u = 0; u < q; ++u) {
          const Vec2d ab{(col + (u + 0.5) / q) / s, (row + (v + 0.5) / q) / s};
          sh_eval(order, glm::normalize(square_to_hemisphere(ab)), y);
          for (int i = 0; i < n; ++i)
            acc += y[static_cast<std::size_t>(i)] *
                   Vec3d(sh.values[p * n + static_cast<std::size_t>(i)]);
        }
      acc *= grid.cell_solid_angle() / (q * q);
      const Vec3d got(pixel.values[p * static_cast<std::size_t>(grid.cell_count()) +
                                   static_cast<std::size_t>(j)]);
      worst = std::max(worst, glm::length(got - acc));
      largest = std::max(largest, glm::length(acc));
    }
  EXPECT_LT(worst, 2e-3 * largest) << "worst " << worst << " of " << largest;
}

TEST(ToPixelBasis, PassesPixelRadianceThroughAndRefusesBadShapes) {
  const HemisphereGrid grid(3);
  LocalRadiance pixel(RadianceBasis::kPixel, 9, 2);
  pixel.values[4] = Rgb(1, 2, 3);
  const LocalRadiance same = to_pixel_basis(pixel, grid);
  EXPECT_EQ(same.values, pixel.values);
  EXPECT_THROW(to_pixel_basis(LocalRadiance(RadianceBasis::kPixel, 16, 1), grid), ParameterError);
  EXPECT_THROW(to_pixel_basis(LocalRadiance(RadianceBasis::kSphericalHarmonics, 10, 1), grid),
               ParameterError);
}

}  // namespace
}  // namespace prt
