#pragma once
// Quadrature rules over a zone of the unit sphere, z in [z_min, z_max] (z the polar axis; the
// upper hemisphere is [0, 1], the whole sphere [-1, 1]). In the coordinates (phi, z) the solid
// angle element is dphi dz (Archimedes), so a product rule in phi and z needs no Jacobian.
//
// Exactness for spherical harmonics (spherical_harmonics.h): a product y_i y_k of functions of
// orders <= N, or a band-limited f of order N times y_k, is in phi a trigonometric polynomial of
// degree <= 2 (N - 1); its coefficient of cos(m phi) or sin(m phi) that survives the phi
// integral is a polynomial in z of degree <= 2 (N - 1). So the Gauss rule below is exact (to
// rounding) for those integrands when phi_nodes > 2 (N - 1) and z_nodes >= N.
#include <vector>

#include "prtlab/base/types.h"

namespace prt {

/// Gauss-Legendre nodes (increasing) and weights on [a, b]: exact for every polynomial of
/// degree <= 2 count - 1. Throws ParameterError unless 1 <= count <= 256 and a < b.
struct GaussLegendreRule {
  std::vector<double> nodes;
  std::vector<double> weights;
};
GaussLegendreRule gauss_legendre(int count, double a, double b);

struct SphereQuadratureNode {
  Vec3d direction;  ///< unit
  double weight;    ///< solid angle (steradians); the weights of a rule sum to 2 pi (z_max - z_min)
};

/// Gauss-Legendre in z (z_nodes) times phi_nodes equally spaced angles
/// phi_k = 2 pi (k + 1/2) / phi_nodes of weight 2 pi / phi_nodes each (the periodic trapezoid
/// rule: exact for trigonometric polynomials of degree < phi_nodes). Throws ParameterError
/// unless -1 <= z_min < z_max <= 1 and both counts are >= 1.
std::vector<SphereQuadratureNode> zone_gauss_rule(double z_min, double z_max, int z_nodes,
                                                  int phi_nodes);

/// Product midpoint rule: z_cells equal cells in z times phi_cells equal cells in phi, one node
/// at each cell's centre. Exact in phi as zone_gauss_rule; in z, for an integrand whose phi
/// integral g(z) is smooth, the error is at most h^2 / 24 (z_max - z_min) max |g''|,
/// h = (z_max - z_min) / z_cells.
std::vector<SphereQuadratureNode> zone_midpoint_rule(double z_min, double z_max, int z_cells,
                                                     int phi_cells);

}  // namespace prt
