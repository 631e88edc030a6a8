#pragma once
// Mode `abrdf` of material svd: every ABRDF of every texel and colour channel, the V x M matrix
// F(v, j) = b(texel, v, j, channel), truncated to rank K by its exact SVD (Eigen's BDCSVD in
// double). Eckart-Young: no rank-K matrix is closer to F in the Frobenius norm, and the
// truncation's squared residual is the sum of the discarded squared singular values.
#include "prtlab/btf/btf.h"
#include "svd/svd_material.h"

namespace prt::svd {

/// The truncation of every ABRDF of `btf` to rank `rank` (1 <= rank <= min(V, M), else a
/// ParameterError naming `rank` and the BTF); parallel over texels, deterministic.
SvdState truncate_abrdfs(const Btf& btf, int rank);

}  // namespace prt::svd
