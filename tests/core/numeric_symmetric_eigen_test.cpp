// The top eigenpairs of numeric/symmetric_eigen against Eigen's own solver, and the same bits
// when many threads call it at once as when one thread calls it (the LAPACK it may go through
// keeps internal buffers: a call that shared them with another would differ).
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <Eigen/QR>
#include <random>
#include <vector>

#include "prtlab/numeric/symmetric_eigen.h"

namespace prt {
namespace {

// A symmetric positive semi-definite matrix with a decaying, well-separated spectrum.
Eigen::MatrixXd gram(Eigen::Index n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  Eigen::MatrixXd b(n, n);
  for (Eigen::Index i = 0; i < b.size(); ++i) b.data()[i] = g(rng);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(b);
  const Eigen::MatrixXd q = qr.householderQ();
  Eigen::VectorXd s(n);
  for (Eigen::Index j = 0; j < n; ++j) s[j] = 100.0 * std::pow(0.97, static_cast<double>(j));
  return q * s.asDiagonal() * q.transpose();
}

TEST(SymmetricEigen, TopPairsMatchEigensSolver) {
  for (const Eigen::Index k : {4, 40, 120}) {
    const Eigen::MatrixXd a = gram(160, 7 + static_cast<std::uint64_t>(k));
    const SymmetricEigen got = top_symmetric_eigen(a, k);
    const SymmetricEigen want = top_symmetric_eigen_eigen(a, k);
    ASSERT_EQ(got.vectors.cols(), k);
    for (Eigen::Index j = 0; j < k; ++j) {
      EXPECT_NEAR(got.values[j], want.values[j], 1e-10 * want.values[0]) << "k " << k << " j " << j;
      // Eigenvectors up to sign; the gaps (3 % of the value) bound the angle by ~1e-12 / gap.
      EXPECT_NEAR(std::abs(got.vectors.col(j).dot(want.vectors.col(j))), 1.0, 1e-8)
          << "k " << k << " j " << j;
      EXPECT_LT((a * got.vectors.col(j) - got.values[j] * got.vectors.col(j)).norm(),
                1e-10 * want.values[0]);
    }
  }
}

TEST(SymmetricEigen, ConcurrentCallsGiveTheBitsOfSerialOnes) {
  constexpr int kProblems = 24;
  std::vector<Eigen::MatrixXd> problems;
  for (int p = 0; p < kProblems; ++p) problems.push_back(gram(96 + 16 * (p % 5), 100 + p));
  std::vector<SymmetricEigen> serial;
  for (const Eigen::MatrixXd& a : problems) serial.push_back(top_symmetric_eigen(a, a.rows() / 3));
  for (int round = 0; round < 4; ++round) {
    std::vector<SymmetricEigen> together(kProblems);
    tbb::parallel_for(0, kProblems, [&](int p) {
      together[p] = top_symmetric_eigen(problems[p], problems[p].rows() / 3);
    });
    for (int p = 0; p < kProblems; ++p) {
      ASSERT_EQ(together[p].values, serial[p].values) << "problem " << p << " round " << round;
      ASSERT_EQ(together[p].vectors, serial[p].vectors) << "problem " << p << " round " << round;
    }
  }
}

TEST(SymmetricEigen, NamesItsBackend) {
  const std::string name = symmetric_eigen_backend();
  EXPECT_TRUE(name.find("LAPACK") != std::string::npos || name.find("Eigen") != std::string::npos)
      << name;
}

}  // namespace
}  // namespace prt
