#pragma once
// The halfway vector of an ABRDF sample and the Gram-Schmidt halfangle/difference (GSHD)
// parameterisation of Kautz and McCool (1999), on prtlab's hemisphere grids (docs/btf.md
// "Factored materials"). A three-factor material f(d, e) ~ P(d) Q(h) R(e) (Suykens et al. 2003)
// stores Q on a half_side x half_side HemisphereGrid of halfway directions and reads it with
// the sphere-bilinear interpolation of btf_view_samples, so the weights here are the ones
// shading uses: a factorisation fitted through them is exact where shading evaluates it.
//
// Sample order: an ABRDF of a texel is the M x V in/out samples of the BTF, s = view * M + light
// (btf.h's layout, so a texel's values for one channel are read with stride 3).
#include <Eigen/SparseCore>
#include <utility>
#include <vector>

#include "prtlab/base/types.h"
#include "prtlab/btf/btf.h"

namespace prt {

/// normalize(light + view) in float, the view clamped to the hemisphere first
/// (clamp_to_hemisphere) as shading clamps it. Both unit with z >= 0, so the sum is not zero.
Vec3 halfway_f(Vec3 light, Vec3 view_clamped);

/// The 4 halfway-grid samples and weights of the pair (light, view): btf_view_samples on the
/// half grid at halfway_f.
BtfViewSamples halfway_samples(int half_side, Vec3 light, Vec3 view_clamped);

/// The light directions of an S x S grid in float (HemisphereGrid::direction, rounded).
std::vector<Vec3> light_directions_f(int light_side);

/// (M V) x (half_side^2) weights: row s = view * M + light holds halfway_samples of that pair
/// (the view at its grid centre). Q_io = W q is the halfway factor at every in/out sample.
Eigen::SparseMatrix<double, Eigen::RowMajor> halfway_weights(int light_side, int view_side,
                                                             int half_side);

/// The incident and exitant directions of halfway h and difference d (both unit): d is the
/// incident direction in the frame (t', b', h), t' the tangent +x made orthogonal to h by
/// Gram-Schmidt (or +y when h is along x), b' = h x t'; the exitant direction is the incident
/// one mirrored about h.
std::pair<Vec3d, Vec3d> gshd_to_in_out(const Vec3d& h, const Vec3d& d);

/// An ABRDF resampled from the in/out samples to GSHD: F_hd = G f over (half_side^2) x
/// (diff_side^2) cell centres, row a * D + b for halfway cell a and difference cell b. A row is
/// valid when both directions it maps to lie above the horizon; it then interpolates the
/// incident direction on the light grid and the exitant one on the view grid (btf_view_samples
/// on each, 16 weights); an invalid row is empty.
struct GshdResampling {
  int half_side = 0, diff_side = 0;
  Eigen::SparseMatrix<double, Eigen::RowMajor> weights;  ///< (H D) x (M V)
  std::vector<char> valid;                               ///< per row
};
GshdResampling gshd_resampling(int light_side, int view_side, int half_side, int diff_side);

}  // namespace prt
