#include "prtlab/numeric/symmetric_eigen.h"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <vector>

#include "prtlab/base/error.h"

#ifdef PRTLAB_HAVE_LAPACK
extern "C" void dsyevr_(const char* jobz, const char* range, const char* uplo, const int* n,
                        double* a, const int* lda, const double* vl, const double* vu,
                        const int* il, const int* iu, const double* abstol, int* m, double* w,
                        double* z, const int* ldz, int* isuppz, double* work, const int* lwork,
                        int* iwork, const int* liwork, int* info);
#ifdef PRTLAB_OPENBLAS_REENTRANT
extern "C" void openblas_set_num_threads(int num_threads);
#endif
#endif

namespace prt {
namespace {

void check(const Eigen::MatrixXd& g, Eigen::Index k) {
  if (g.rows() != g.cols())
    throw ParameterError(
        fmt::format("symmetric eigen-decomposition of a {} x {} matrix", g.rows(), g.cols()));
  if (k < 0 || k > g.rows())
    throw ParameterError(
        fmt::format("{} eigenpairs asked of a {} x {} matrix", k, g.rows(), g.cols()));
}

#ifdef PRTLAB_HAVE_LAPACK
// PRTLAB_EIGEN_SOLVER=eigen runs Eigen's solver in a build with LAPACK, so one binary measures
// the two against each other in one run (scripts/arch_ab.sh, results/bench/lapack-ab/).
bool eigen_forced() {
  static const bool forced = [] {
    const char* v = std::getenv("PRTLAB_EIGEN_SOLVER");
    return v != nullptr && std::strcmp(v, "eigen") == 0;
  }();
  return forced;
}
#endif

}  // namespace

SymmetricEigen top_symmetric_eigen_eigen(const Eigen::MatrixXd& g, Eigen::Index k) {
  check(g, k);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(g);
  if (eig.info() != Eigen::Success)
    throw Error(
        fmt::format("the eigen-decomposition of a {} x {} symmetric matrix did not converge",
                    g.rows(), g.cols()));
  return {eig.eigenvalues().tail(k).reverse(), eig.eigenvectors().rightCols(k).rowwise().reverse()};
}

#ifdef PRTLAB_HAVE_LAPACK
SymmetricEigen top_symmetric_eigen(const Eigen::MatrixXd& g, Eigen::Index k) {
  if (eigen_forced()) return top_symmetric_eigen_eigen(g, k);
  check(g, k);
  const auto n = static_cast<int>(g.rows());
  if (n == 0 || k == 0) return {Eigen::VectorXd(0), Eigen::MatrixXd(g.rows(), 0)};
  // The top k only ('I') when they are a small part of the spectrum; past that dsyevr's MRRR is
  // as fast over all of it ('A'), which the light Gram matrices of srbf_cta (134 of 642) showed.
  const bool subset = 8 * k <= n;
  const char* range = subset ? "I" : "A";
  const int cols = subset ? static_cast<int>(k) : n;
  Eigen::MatrixXd a = g;
  Eigen::VectorXd w(n);
  Eigen::MatrixXd z(n, cols);
  std::vector<int> isuppz(static_cast<std::size_t>(2 * n));
  int m = 0, info = 0, lwork = -1, liwork = -1, iwork_query = 0;
  const int il = subset ? n - cols + 1 : 1, iu = n;
  const double vl = 0, vu = 0, abstol = 0;
  double work_query = 0;
#ifdef PRTLAB_OPENBLAS_REENTRANT
  // The pthread build locks its buffers, so TBB's threads may call it together; its own threads
  // would oversubscribe the cores (and make the result depend on their count).
  static const bool one_thread = [] {
    openblas_set_num_threads(1);
    return true;
  }();
  (void)one_thread;
#else
  // Debian's serial OpenBLAS shares internal buffers between calls without locking them: two
  // threads inside it at once corrupt each other's results. One call at a time.
  static std::mutex serial;
  const std::lock_guard lock(serial);
#endif
  dsyevr_("V", range, "L", &n, a.data(), &n, &vl, &vu, &il, &iu, &abstol, &m, w.data(), z.data(),
          &n, isuppz.data(), &work_query, &lwork, &iwork_query, &liwork, &info);
  if (info != 0) throw Error(fmt::format("dsyevr's workspace query failed (info {})", info));
  lwork = static_cast<int>(work_query);
  liwork = iwork_query;
  std::vector<double> work(static_cast<std::size_t>(lwork));
  std::vector<int> iwork(static_cast<std::size_t>(liwork));
  dsyevr_("V", range, "L", &n, a.data(), &n, &vl, &vu, &il, &iu, &abstol, &m, w.data(), z.data(),
          &n, isuppz.data(), work.data(), &lwork, iwork.data(), &liwork, &info);
  if (info != 0 || m != cols)
    throw Error(fmt::format(
        "the eigen-decomposition of a {} x {} symmetric matrix did not converge (dsyevr info {})",
        n, n, info));
  // Ascending either way: the k largest are the last k of the m found.
  return {w.segment(m - k, k).reverse(), z.rightCols(k).rowwise().reverse()};
}

const char* symmetric_eigen_backend() {
  return eigen_forced() ? "Eigen SelfAdjointEigenSolver (PRTLAB_EIGEN_SOLVER=eigen)"
#ifdef PRTLAB_OPENBLAS_REENTRANT
                        : "LAPACK dsyevr (OpenBLAS pthread build, one thread a call)";
#else
                        : "LAPACK dsyevr (OpenBLAS, serial)";
#endif
}
#else
SymmetricEigen top_symmetric_eigen(const Eigen::MatrixXd& g, Eigen::Index k) {
  return top_symmetric_eigen_eigen(g, k);
}

const char* symmetric_eigen_backend() {
  return "Eigen SelfAdjointEigenSolver";
}
#endif

}  // namespace prt
