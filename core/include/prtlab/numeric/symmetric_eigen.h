#pragma once
// The top eigenpairs of a dense symmetric matrix. Built with a LAPACK (PRTLAB_LAPACK, Debian's
// OpenBLAS), it calls dsyevr: OpenBLAS picks kernels for the CPU it runs on (AVX2, AVX-512) even
// in a portable build, and its tridiagonalisation is several times faster than Eigen's
// SelfAdjointEigenSolver on the 642 x 642 light Gram matrices of srbf_cta. Without, Eigen's
// solver. Either way the result is the same on any number of threads: OpenBLAS runs each call on
// the calling thread only (the pthread build pinned to one thread, several calls at once; the
// serial build one call at a time). PRTLAB_EIGEN_SOLVER=eigen in the environment selects Eigen's
// solver in a build with LAPACK (for measuring one against the other).
#include <Eigen/Core>

namespace prt {

struct SymmetricEigen {
  Eigen::VectorXd values;   ///< k largest eigenvalues, decreasing
  Eigen::MatrixXd vectors;  ///< n x k, orthonormal, column j for values[j]
};

/// The k largest eigenpairs of the symmetric matrix g (its lower triangle is read). Throws Error
/// when the solver fails, ParameterError when g is not square or k is not in 0..n.
SymmetricEigen top_symmetric_eigen(const Eigen::MatrixXd& g, Eigen::Index k);

/// "LAPACK dsyevr (OpenBLAS ...)" or "Eigen SelfAdjointEigenSolver": what the build uses,
/// for provenance and benchmarks.
const char* symmetric_eigen_backend();

/// Eigen's solver whatever the build, for benchmarks and tests that compare the two.
SymmetricEigen top_symmetric_eigen_eigen(const Eigen::MatrixXd& g, Eigen::Index k);

}  // namespace prt
