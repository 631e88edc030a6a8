#include "prtlab/sphere/sphere_quadrature.h"

#include <cmath>
#include <numbers>

#include "prtlab/base/error.h"

namespace prt {

namespace {

void check_zone(double z_min, double z_max, int z_count, int phi_count, const char* what) {
  if (!(z_min >= -1.0 && z_min < z_max && z_max <= 1.0)) {
    throw ParameterError(fmt::format(
        "{}: zone z in [{}, {}] is not inside -1 <= z_min < z_max <= 1", what, z_min, z_max));
  }
  if (z_count < 1 || phi_count < 1) {
    throw ParameterError(fmt::format("{}: need at least one node in z and in phi, got {} and {}",
                                     what, z_count, phi_count));
  }
}

Vec3d direction_at(double z, double phi) {
  // max() keeps sqrt's argument non-negative where 1 - z^2 rounds below 0.
  const double s = std::sqrt(std::max(0.0, (1.0 - z) * (1.0 + z)));
  return {s * std::cos(phi), s * std::sin(phi), z};
}

std::vector<SphereQuadratureNode> product_rule(const std::vector<double>& z,
                                               const std::vector<double>& wz, int phi_nodes) {
  std::vector<SphereQuadratureNode> out;
  out.reserve(z.size() * static_cast<std::size_t>(phi_nodes));
  const double dphi = kTwoPi / phi_nodes;
  for (std::size_t j = 0; j < z.size(); ++j) {
    for (int k = 0; k < phi_nodes; ++k) {
      out.push_back({direction_at(z[j], (k + 0.5) * dphi), wz[j] * dphi});
    }
  }
  return out;
}

}  // namespace

// Newton's method on P_n from the Chebyshev-like first guess cos(pi (i + 3/4) / (n + 1/2)),
// with P_n and P_n' from the three-term recurrence: converges quadratically to every root, and
// the weights 2 / ((1 - x^2) P_n'(x)^2) come from the same evaluation.
GaussLegendreRule gauss_legendre(int count, double a, double b) {
  if (count < 1 || count > 256) {
    throw ParameterError(
        fmt::format("gauss_legendre: node count must be in [1, 256], got {}", count));
  }
  if (!(a < b))
    throw ParameterError(fmt::format("gauss_legendre: interval [{}, {}] is empty", a, b));
  GaussLegendreRule rule;
  rule.nodes.resize(count);
  rule.weights.resize(count);
  const double half = 0.5 * (b - a), mid = 0.5 * (a + b);
  for (int i = 0; i < (count + 1) / 2; ++i) {
    double x = std::cos(std::numbers::pi * (i + 0.75) / (count + 0.5));
    double dp = 0.0;
    // One more step after the update falls to rounding level polishes the last bit.
    for (int iter = 0, polish = 0; iter < 100 && polish < 2; ++iter) {
      double prev = 1.0, p = x;  // P_{k-1}, P_k, from k = 1 up to k = count
      for (int k = 2; k <= count; ++k) {
        const double next = ((2.0 * k - 1.0) * x * p - (k - 1.0) * prev) / k;
        prev = p;
        p = next;
      }
      dp = count * (x * p - prev) / (x * x - 1.0);
      const double dx = p / dp;
      x -= dx;
      if (std::abs(dx) <= 1e-15) ++polish;
    }
    const double w = 2.0 / ((1.0 - x * x) * dp * dp);
    // Roots come in pairs +-x; node i from the top, its mirror from the bottom.
    rule.nodes[count - 1 - i] = mid + half * x;
    rule.nodes[i] = mid - half * x;
    rule.weights[count - 1 - i] = half * w;
    rule.weights[i] = half * w;
  }
  return rule;
}

std::vector<SphereQuadratureNode> zone_gauss_rule(double z_min, double z_max, int z_nodes,
                                                  int phi_nodes) {
  check_zone(z_min, z_max, z_nodes, phi_nodes, "zone_gauss_rule");
  const GaussLegendreRule g = gauss_legendre(z_nodes, z_min, z_max);
  return product_rule(g.nodes, g.weights, phi_nodes);
}

std::vector<SphereQuadratureNode> zone_midpoint_rule(double z_min, double z_max, int z_cells,
                                                     int phi_cells) {
  check_zone(z_min, z_max, z_cells, phi_cells, "zone_midpoint_rule");
  const double h = (z_max - z_min) / z_cells;
  std::vector<double> z(z_cells), w(z_cells, h);
  for (int j = 0; j < z_cells; ++j) z[j] = z_min + (j + 0.5) * h;
  return product_rule(z, w, phi_cells);
}

}  // namespace prt
