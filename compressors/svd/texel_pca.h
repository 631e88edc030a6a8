#pragma once
// Mode `texel_pca` of material svd: principal component analysis over the texels. Each texel's
// ABRDF (3 M V values, the BTF's own per-texel order) is a row of X (U^2 rows); with the mean row
// m and the centred X_c = X - 1 m, the eigenvectors u_r of the texel Gram matrix G = X_c X_c^T
// (U^2 x U^2, Eigen's SelfAdjointEigenSolver in double) give the principal directions
// X_c^T u_r / |X_c^T u_r|, orthonormalised in order (Gram-Schmidt), and each texel's
// coefficients are the projections of its centred row on them. The squared residual of the K
// leading directions is the sum of the discarded eigenvalues of G (Eckart-Young on X_c).
#include "prtlab/btf/btf.h"
#include "svd/svd_material.h"

namespace prt::svd {

/// The most texels texel_pca takes: the Gram matrix of 4096 texels is 128 MB in double.
inline constexpr int kMaxPcaTexels = 4096;

/// The K = `rank` leading principal components of `btf`'s texels (1 <= rank <= min(U^2, 3MV),
/// else a ParameterError naming `rank` and the BTF; at most kMaxPcaTexels texels).
SvdState texel_pca(const Btf& btf, int rank);

}  // namespace prt::svd
