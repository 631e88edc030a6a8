#pragma once
// A distant light as a sum of spherical radial basis functions (Tsai and Shih 2006, sections 4.1
// and 5.3): L~(eta) = sum_j L_j G(eta . xi_j; lambda_j), RGB coefficients L_j, with
//
//   uniform SRBFs    fixed near-uniform centres (a subdivided icosahedron, or a spherical
//                    Fibonacci set for other counts), one bandwidth from their spacing, and
//                    coefficients by regularised least squares (the dynamic-lighting path);
//   scattered SRBFs  centres, bandwidths and coefficients fitted to the light: heuristic initial
//                    centres from each direction's coverage, then alternating L-BFGS-B steps on
//                    the centres and on the bandwidths (LBFGSpp) with least-squares coefficients
//                    after each, until the squared error stops falling (eq. 20-21).
//
// The error is measured on the cubemap the light is given as: E = sum over pixels k and channels
// of Omega_k (L_k - L~(d_k))^2, the solid-angle weighted discretisation of eq. 20, and reported
// relative, sqrt(E / sum Omega_k L_k^2). A fit's parameter count is 6 per SRBF (two angles, a
// bandwidth, three coefficients) for scattered SRBFs and 3 per SRBF for uniform ones, whose
// centres and bandwidth are implied: the paper's 162 scattered SRBFs are its "972 parameters".
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "prtlab/base/types.h"
#include "prtlab/sphere/cubemap.h"
#include "prtlab/sphere/srbf.h"

namespace prt {

struct SrbfLight {
  SrbfKernel kernel = SrbfKernel::kGaussian;
  std::vector<Vec3d> centres;       ///< unit
  std::vector<double> bandwidths;   ///< one per centre
  std::vector<Vec3d> coefficients;  ///< RGB per centre
  bool scattered = false;           ///< centres and bandwidths fitted (6 parameters an SRBF)

  std::size_t count() const { return centres.size(); }
  std::size_t parameter_count() const { return count() * (scattered ? 6 : 3); }
  /// L~(d), RGB.
  Vec3d evaluate(const Vec3d& d) const;
  /// L~ at every pixel centre of `layout`.
  Cubemap to_cubemap(int resolution) const;
};

/// N near-uniform unit points: the icosphere vertices when N is one of its counts (12, 42, 162,
/// 642, ...), else the spherical Fibonacci set (golden-angle spiral), deterministic.
std::vector<Vec3d> uniform_sphere_points(int count);

/// The Gaussian bandwidth of uniform SRBFs with these centres: sigma = kSpreadPerSpacing x the
/// smallest geodesic distance between two centres, lambda = 1 / sigma^2. The factor makes the
/// paper's configuration come out: 642 icosphere centres with sigma = pi/40.
double uniform_gaussian_bandwidth(std::span<const Vec3d> centres);
double uniform_gaussian_spread_per_spacing();

/// Relative error sqrt(E / sum Omega_k |L_k|^2) of `fit` on `light` (see the file comment).
double srbf_relative_error(const SrbfLight& fit, const Cubemap& light);

/// Coefficients of fixed SRBFs by least squares on the cubemap pixels, solid-angle weighted, with
/// Tikhonov regularisation `ridge` x the largest diagonal entry of the normal matrix (0: none).
/// Fills fit.coefficients; returns the normal matrix' condition number estimate (LDLT pivots).
double fit_srbf_coefficients(SrbfLight& fit, const Cubemap& light, double ridge);

/// Uniform Gaussian SRBFs: `count` centres (uniform_sphere_points), bandwidth from their spacing,
/// least-squares coefficients.
SrbfLight fit_uniform_srbf(const Cubemap& light, int count, double ridge = 1e-9);

/// How the scattered fit picks its initial centres (each with the bandwidth of its coverage):
///   kCoverage  the paper's: by coverage-weighted luminance, each pick marking its cone taken,
///              the cones shrunk by half whenever every direction is marked;
///   kResidual  greedy on the residual (beyond the paper): the next centre where coverage x
///              |residual luminance| is largest, whose SRBF (of the residual's value there) is
///              then subtracted; it does not put two centres on one bright lobe.
enum class SrbfSeeding { kCoverage, kResidual };

struct ScatteredFitOptions {
  int count = 162;
  int rounds = 40;             ///< alternating (centres, bandwidths, coefficients) rounds at most
  int lbfgs_iterations = 30;   ///< per L-BFGS-B step
  double tolerance = 1e-3;     ///< stop when a round lowers E by less than this fraction
  double ridge = 1e-9;         ///< of the coefficient solves (see fit_srbf_coefficients)
  double min_bandwidth = 1.0;  ///< L-BFGS-B bounds of the bandwidths
  double max_bandwidth = 1e5;
  /// Coverage heuristic of the initial centres: a direction's cone grows over its nearest
  /// directions until more than `coverage_ratio` of them differ from it by more than
  /// sqrt(`coverage_threshold`) x its own luminance; the coverage is the cone's radius divided
  /// by sqrt(-2 ln(1 - sqrt(threshold))), the sigma of a Gaussian lobe with that cone, and gives
  /// the initial bandwidth 1 / coverage^2 (0 < threshold < 1).
  double coverage_threshold = 0.05;
  double coverage_ratio = 0.2;
  SrbfSeeding seeding = SrbfSeeding::kCoverage;
  /// Called after each round with (round, relative error).
  std::function<void(int, double)> on_round;
};

struct ScatteredFitReport {
  double initial_error = 0;  ///< relative error of the heuristic initial SRBFs
  double error = 0;          ///< of the result
  int rounds = 0;
  int lbfgs_failures = 0;  ///< L-BFGS-B steps stopped by their line search (kept the best point)
};

/// The scattered SRBF fit of section 5.3 (Gaussian kernels).
SrbfLight fit_scattered_srbf(const Cubemap& light, const ScatteredFitOptions& options,
                             ScatteredFitReport* report = nullptr);

}  // namespace prt
