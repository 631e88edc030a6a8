#pragma once
// Local radiance in any basis, evaluated at the local bins d_j: the one function through which
// evaluation, the conformance suite, the frame loop and images accept a backend whose relight
// is not in the pixel basis.
//
// A pixel-basis L*_j is the transferred radiance integrated over cell j of the hemisphere grid
// (T_p[j, k] = v_k for the pixels k whose local direction falls in cell j, and L_k carries the
// pixel's solid angle). A backend in SH basis returns per vertex the coefficients c_i of the
// transferred radiance f = sum_i c_i y_i in the local frame, so its value in the pixel basis is
//
//   L*_j = integral over cell j of f = sum_i B[j, i] c_i,   B[j, i] = integral over cell j of y_i,
//
// with B computed once per (grid, order) by the midpoint rule on q x q sub-squares of each cell
// (the concentric map preserves area, so each sub-square has solid angle 2 pi / (S^2 q^2)).
#include <span>
#include <vector>

#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/transfer/local_radiance.h"

namespace prt {

/// B (M x order^2, row-major) for `grid`. `subdivisions` = q per cell side.
std::vector<double> sh_cell_integrals(const HemisphereGrid& grid, int order, int subdivisions = 16);

/// The pixel-basis equivalent of `radiance` on `grid`: a pixel-basis input is returned as it
/// is (after a shape check), an SH one is mapped through B per vertex (float output, double
/// accumulation). Throws ParameterError for a dim that is no square of an order <= 10 or a
/// pixel dim other than M.
LocalRadiance to_pixel_basis(const LocalRadiance& radiance, const HemisphereGrid& grid);

}  // namespace prt
