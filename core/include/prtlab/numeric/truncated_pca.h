#pragma once
// The top-k principal components of a set of rows, dense or CSR, in double precision, without
// ever forming the n x n covariance: with few rows it eigen-decomposes the m x m Gram matrix of
// the centred rows, otherwise it runs a block subspace iteration in which the centred operator
// x -> x - mean is applied implicitly, so a sparse row costs its non-zeros. CPCA runs this per
// cluster on rows of T (6,144 columns, about 50 non-zeros each).
#include <Eigen/Core>
#include <cstdint>

#include "prtlab/numeric/row_set.h"

namespace prt {

enum class PcaMethod {
  /// Gram when rows <= min(gram_max_rows, cols) or rows < components, else subspace: the Gram
  /// eigen-decomposition costs m^3, the subspace iteration is exact in one step when the block
  /// spans all n columns.
  kAuto,
  kGram,      ///< eigen-decomposition of the m x m matrix C C^T
  kSubspace,  ///< block subspace iteration with Rayleigh-Ritz on the implicit C^T C
  /// Spectra's implicitly restarted Lanczos (SymEigsSolver) on the implicit C^T C: one
  /// matrix-vector product per step, for a one-off PCA of a large cluster.
  kLanczos,
};

struct TruncatedPcaOptions {
  int components = 1;
  PcaMethod method = PcaMethod::kAuto;
  std::size_t gram_max_rows = 512;
  /// Extra block vectors of the subspace iteration: convergence goes as
  /// (sigma_{k+oversampling} / sigma_k)^2 per iteration, so a few more than k pay for themselves.
  int oversampling = 8;
  int max_iterations = 500;
  /// The subspace iteration stops when every kept Ritz pair has a residual
  /// ||S u - lambda u|| <= tolerance * lambda_max, S = C^T C.
  double tolerance = 1e-10;
  std::uint64_t seed = 0;  ///< the random start block of the subspace iteration
  /// Warm start of the subspace iteration (n x j, any j): its columns open the start block and
  /// random ones fill the rest. Rayleigh-Ritz then works on a span that contains these columns,
  /// so the components found capture at least as much of the scatter as they do. CPCA passes a
  /// cluster's previous components, which after a reclassification are nearly converged.
  Eigen::MatrixXd start;
  /// false: components of the raw rows (mean reported as zero), for fits that keep no mean.
  bool center = true;
};

/// C is the m x n matrix of centred rows x_i - mean, S = C^T C its scatter matrix (the
/// covariance times m). The components are the top eigenvectors of S.
struct TruncatedPca {
  Eigen::VectorXd mean;              ///< n
  Eigen::MatrixXd components;        ///< n x k, orthonormal columns, decreasing eigenvalue
  Eigen::VectorXd eigenvalues;       ///< k eigenvalues of S, decreasing (variance times m)
  Eigen::VectorXd singular_values;   ///< k singular values of C, sqrt(eigenvalues)
  double total_squared_error = 0.0;  ///< sum_i ||x_i - mean||^2 = trace(S)
  /// sum_i ||x_i - mean - U U^T (x_i - mean)||^2 = trace(S) - sum(eigenvalues), i.e. the sum of
  /// the discarded eigenvalues.
  double residual_squared_error = 0.0;
  PcaMethod method = PcaMethod::kAuto;  ///< the path that ran (kGram or kSubspace)
  int iterations = 0;                   ///< subspace iterations (0 for Gram)
};

/// Throws ParameterError when components is not in 1..cols or the set has no rows, and when
/// kSubspace is forced with fewer rows than components. Components beyond the rank of C have
/// eigenvalue 0 and complete the basis orthonormally. The sign of each component is fixed (its
/// entry of largest magnitude is positive) so that results are reproducible.
TruncatedPca truncated_pca(const RowSet& rows, const TruncatedPcaOptions& options);

/// m x k coefficients (x_i - mean) . u_j of each row on each component.
Eigen::MatrixXd pca_coefficients(const RowSet& rows, const TruncatedPca& pca);

/// Per row, ||x_i - mean - U U^T (x_i - mean)||^2 (clamped at 0), the error CPCA reclassifies by.
Eigen::VectorXd pca_row_squared_errors(const RowSet& rows, const TruncatedPca& pca);

}  // namespace prt
