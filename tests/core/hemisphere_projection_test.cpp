// The least-squares hemispherical SH projection and its error analysis (Sloan et al. 2003,
// appendix 9): the Gram matrix A over H three independent ways (Gauss-Legendre with sh_eval's
// z-parts, the Rodrigues closed form, a product midpoint rule through sh_eval), its structure,
// its spectrum and Schur complements, the projector c = A^+ b with its near-singular handling,
// and the error matrices Q checked against explicit quadrature of the reflected functions.
#include "prtlab/sphere/hemisphere_projection.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <random>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/sphere/spherical_harmonics.h"

namespace prt {
namespace {

constexpr std::uint64_t kSeed = 20030727;
constexpr double kEps = std::numeric_limits<double>::epsilon();

Eigen::VectorXd random_unit(int n, std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  Eigen::VectorXd c(n);
  for (int i = 0; i < n; ++i) c[i] = g(rng);
  return c / c.norm();
}

double a_norm(const Eigen::MatrixXd& a, const Eigen::VectorXd& x) {
  return std::sqrt(std::max(0.0, x.dot(a * x)));
}

// Rows y(d_j) for every node of a rule, order^2 columns.
Eigen::MatrixXd sh_rows(int order, const std::vector<SphereQuadratureNode>& nodes,
                        bool mirror = false) {
  Eigen::MatrixXd y(static_cast<Eigen::Index>(nodes.size()), sh_count(order));
  std::array<double, sh_count(kMaxShOrder)> v{};
  for (std::size_t j = 0; j < nodes.size(); ++j) {
    Vec3d d = nodes[j].direction;
    if (mirror) d.z = -d.z;
    sh_eval(order, d, v);
    for (int i = 0; i < sh_count(order); ++i) y(j, i) = v[i];
  }
  return y;
}

Eigen::VectorXd weights(const std::vector<SphereQuadratureNode>& nodes) {
  Eigen::VectorXd w(static_cast<Eigen::Index>(nodes.size()));
  for (std::size_t j = 0; j < nodes.size(); ++j) w[j] = nodes[j].weight;
  return w;
}

TEST(GaussLegendre, ExactToDegreeTwoNMinusOneAndNotBeyond) {
  for (int count : {1, 2, 5, 10, 20}) {
    const GaussLegendreRule r = gauss_legendre(count, 0.0, 1.0);
    for (int k = 0; k <= 2 * count; ++k) {
      double sum = 0.0;
      for (int j = 0; j < count; ++j) sum += r.weights[j] * std::pow(r.nodes[j], k);
      const double want = 1.0 / (k + 1);
      if (k <= 2 * count - 1) {
        EXPECT_NEAR(sum, want, 8 * count * kEps) << "count " << count << " degree " << k;
      } else {
        // The rule's error on x^(2n) over [0, 1] is n!^4 / ((2n + 1) (2n)!^2), positive.
        const double nf = std::tgamma(count + 1.0), n2f = std::tgamma(2.0 * count + 1.0);
        const double err = nf * nf * nf * nf / ((2.0 * count + 1.0) * n2f * n2f);
        EXPECT_NEAR(want - sum, err, 1e-6 * err + 8 * count * kEps) << "count " << count;
      }
    }
    EXPECT_TRUE(std::is_sorted(r.nodes.begin(), r.nodes.end()));
  }
  EXPECT_THROW(gauss_legendre(0, 0.0, 1.0), ParameterError);
  EXPECT_THROW(gauss_legendre(3, 1.0, 1.0), ParameterError);
}

TEST(HemisphereGram, FullSphereIsTheIdentity) {
  for (int order = 1; order <= kMaxShOrder; ++order) {
    const int n = sh_count(order);
    const Eigen::MatrixXd eye = Eigen::MatrixXd::Identity(n, n);
    EXPECT_LT((sh_zone_gram(order, -1.0, 1.0) - eye).cwiseAbs().maxCoeff(), 64 * kEps)
        << "order " << order;
    EXPECT_LT((sh_zone_gram_closed_form(order, -1.0, 1.0) - eye).cwiseAbs().maxCoeff(), 1e-13)
        << "order " << order;
    // Through sh_eval at every phi: checks the sin(|m| phi) functions too.
    const auto rule = zone_gauss_rule(-1.0, 1.0, order, 2 * order - 1);
    EXPECT_LT((sh_gram(order, rule) - eye).cwiseAbs().maxCoeff(), 64 * kEps) << "order " << order;
  }
}

TEST(HemisphereGram, ExactClosedFormAndQuadratureAgree) {
  for (int order = 1; order <= kMaxShOrder; ++order) {
    const Eigen::MatrixXd a = hemisphere_gram(order);
    const Eigen::MatrixXd closed = sh_zone_gram_closed_form(order, 0.0, 1.0);
    const double diff = (a - closed).cwiseAbs().maxCoeff();
    EXPECT_LT(diff, 1e-12) << "order " << order;
    // The Gauss product rule through sh_eval at arbitrary phi is exact for these integrands.
    const auto rule = zone_gauss_rule(0.0, 1.0, order, 2 * order - 1);
    EXPECT_LT((sh_gram(order, rule) - a).cwiseAbs().maxCoeff(), 64 * kEps) << "order " << order;
  }
}

TEST(HemisphereGram, MidpointRuleWithinItsBoundAndSecondOrder) {
  const int order = 5;
  const Eigen::MatrixXd a = hemisphere_gram(order);
  const int phi_cells = 2 * order - 1;
  const int z_cells = 1024;
  const Eigen::MatrixXd mid = sh_gram(order, zone_midpoint_rule(0.0, 1.0, z_cells, phi_cells));
  const double bound = sh_gram_midpoint_error_bound(order, 0.0, 1.0, z_cells);
  const double err = (mid - a).cwiseAbs().maxCoeff();
  EXPECT_LE(err, bound);
  EXPECT_GT(err, 0.0);
  // The midpoint rule's error is c h^2 + O(h^4) per entry: halving h divides it by 4. A wrong
  // exact matrix would leave a constant offset and break the ratio.
  const Eigen::MatrixXd e64 = sh_gram(order, zone_midpoint_rule(0.0, 1.0, 64, phi_cells)) - a;
  const Eigen::MatrixXd e128 = sh_gram(order, zone_midpoint_rule(0.0, 1.0, 128, phi_cells)) - a;
  const double ratio = e64.cwiseAbs().maxCoeff() / e128.cwiseAbs().maxCoeff();
  EXPECT_GT(ratio, 3.9);
  EXPECT_LT(ratio, 4.1);
  EXPECT_LT((e64 - 4.0 * e128).cwiseAbs().maxCoeff(), 0.01 * e64.cwiseAbs().maxCoeff());
}

TEST(HemisphereGram, StructureSymmetryAndDefiniteness) {
  for (int order : {1, 2, 5, 8, 10}) {
    const Eigen::MatrixXd a = hemisphere_gram(order);
    const int n = sh_count(order);
    EXPECT_EQ((a - a.transpose()).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_NEAR(a(0, 0), 0.5, 4 * kEps);
    for (int l = 0; l < order; ++l) {
      for (int m = -l; m <= l; ++m) {
        const int i = sh_index(l, m);
        EXPECT_NEAR(a(i, i), 0.5, 16 * kEps) << l << "," << m;
        for (int lp = 0; lp < order; ++lp) {
          for (int mp = -lp; mp <= lp; ++mp) {
            const int k = sh_index(lp, mp);
            if (m != mp) {
              EXPECT_EQ(a(i, k), 0.0) << i << "," << k;
            } else if (l != lp && (l + lp) % 2 == 0) {
              EXPECT_NEAR(a(i, k), 0.0, 16 * kEps) << i << "," << k;
            }
          }
        }
      }
    }
    if (order >= 2) {
      // y_0 y_2 = sqrt(3) z / (4 pi) and the integral of z over H is pi.
      EXPECT_NEAR(a(0, sh_index(1, 0)), std::sqrt(3.0) / 4.0, 4 * kEps);
    }
    const Eigen::VectorXd lambda = hemisphere_gram_eigenvalues(order);
    ASSERT_EQ(lambda.size(), n);
    EXPECT_GT(lambda.minCoeff(), 0.0);
    EXPECT_LE(lambda.maxCoeff(), 1.0);  // the hemisphere part of a unit-norm function
    // trace(A) = n / 2 since every A_ii = 1/2.
    EXPECT_NEAR(lambda.sum(), 0.5 * n, 64 * n * kEps) << "order " << order;
    // Each block is I/2 + [[0, B], [B^T, 0]] in even/odd-l order: the spectrum is symmetric
    // about 1/2.
    for (int k = 0; k < n; ++k)
      EXPECT_NEAR(lambda[k] + lambda[n - 1 - k], 1.0, 64 * kEps) << "order " << order << " " << k;
  }
}

TEST(HemisphereGram, EigenvaluesMatchTheFormedMatrix) {
  for (int order = 2; order <= 6; ++order) {
    const Eigen::MatrixXd a = sh_zone_gram_closed_form(order, 0.0, 1.0);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(a, Eigen::EigenvaluesOnly);
    Eigen::VectorXd want = eig.eigenvalues().reverse();
    const Eigen::VectorXd got = hemisphere_gram_eigenvalues(order);
    // The formed matrix's eigenvalues carry absolute errors of about n eps.
    EXPECT_LT((got - want).cwiseAbs().maxCoeff(), 64 * sh_count(order) * kEps) << order;
    EXPECT_TRUE(std::is_sorted(got.data(), got.data() + got.size(), std::greater<>()));
  }
  // Smallest eigenvalues fall by about 30x per order: the near-redundancy the paper points at.
  double previous = 1.0;
  for (int order = 2; order <= kMaxShOrder; ++order) {
    const double smallest = hemisphere_gram_eigenvalues(order).minCoeff();
    EXPECT_LT(smallest, previous / 10.0) << order;
    previous = smallest;
  }
}

TEST(HemisphereGram, DiscardErrorsAreSchurComplements) {
  for (int order = 2; order <= 6; ++order) {
    const int n = sh_count(order);
    const Eigen::VectorXd e = hemisphere_discard_errors(order);
    // 1 / (A^-1)_ii from the closed-form matrix: its relative error is about eps cond(A).
    const Eigen::MatrixXd a = sh_zone_gram_closed_form(order, 0.0, 1.0);
    const Eigen::MatrixXd inv = a.ldlt().solve(Eigen::MatrixXd::Identity(n, n));
    const Eigen::VectorXd lambda = hemisphere_gram_eigenvalues(order);
    const double cond = lambda.maxCoeff() / lambda.minCoeff();
    for (int i = 0; i < n; ++i) {
      EXPECT_NEAR(e[i], 1.0 / inv(i, i), 64 * n * kEps * cond * e[i]) << order << " " << i;
      EXPECT_LE(e[i], a(i, i) * (1 + 1e-15));  // approximating by more functions cannot hurt
    }
  }
  // The smallest is the l = 1, m = 0 function (linear in z), as the paper says.
  for (int order = 3; order <= kMaxShOrder; ++order) {
    const Eigen::VectorXd e = hemisphere_discard_errors(order);
    Eigen::Index arg = 0;
    e.minCoeff(&arg);
    EXPECT_EQ(arg, sh_index(1, 0)) << "order " << order;
  }
}

TEST(HemisphereGram, DiscardErrorIsTheResidualOfTheBestFit) {
  // Fit y_(1,0) on H by the other order-5 functions through the dropped-basis projector and
  // measure the residual by quadrature: its squared integral is the discard error.
  const int order = 5, i = sh_index(1, 0);
  const auto rule = zone_gauss_rule(0.0, 1.0, 2 * order, 4 * order);
  const auto yi = [i](const Vec3d& d) {
    std::array<double, 25> v{};
    sh_eval(5, d, v);
    return v[i];
  };
  const Eigen::VectorXd b = sh_quadrature_projection(order, rule, yi);
  const HemisphereProjector drop(order, {.dropped_index = i});
  const Eigen::VectorXd fit = drop.solve(b);
  EXPECT_EQ(fit[i], 0.0);
  const Eigen::MatrixXd y = sh_rows(order, rule);
  const Eigen::VectorXd r = y * fit - y.col(i);
  const double residual = r.cwiseAbs2().dot(weights(rule));
  const double e = hemisphere_discard_errors(order)[i];
  EXPECT_NEAR(residual, e, 1e-9 * e);
}

TEST(HemisphereProjector, ReproducesBandLimitedFunctionsOnH) {
  std::mt19937_64 rng(kSeed);
  SCOPED_TRACE(testing::Message() << "seed " << kSeed);
  for (int order = 1; order <= 8; ++order) {
    const int n = sh_count(order);
    const Eigen::MatrixXd a = sh_zone_gram_closed_form(order, 0.0, 1.0);
    const HemisphereProjector proj(order);
    EXPECT_EQ(proj.cut_directions(), 0);
    const double lmin = proj.smallest_kept_eigenvalue(), lmax = proj.largest_eigenvalue();
    const auto rule = zone_gauss_rule(0.0, 1.0, order + 1, 2 * order + 1);
    for (int trial = 0; trial < 5; ++trial) {
      const Eigen::VectorXd c = random_unit(n, rng);
      const auto f = [&](const Vec3d& d) {
        std::array<double, sh_count(kMaxShOrder)> v{};
        sh_eval(order, d, v);
        return Eigen::Map<const Eigen::VectorXd>(v.data(), n).dot(c);
      };
      const Eigen::VectorXd b = sh_quadrature_projection(order, rule, f);
      const double delta = (b - a * c).norm();  // quadrature rounding in b
      const Eigen::VectorXd got = proj.solve(b);
      const double solve_rounding = 64 * n * kEps * (lmax / lmin);
      EXPECT_LE((got - c).norm(), delta / lmin + solve_rounding) << "order " << order;
      EXPECT_LE(a_norm(a, got - c), delta / std::sqrt(lmin) + solve_rounding * std::sqrt(lmax))
          << "order " << order;
      if (order >= 2) {
        // The zero-hemisphere coefficients themselves are far from c.
        EXPECT_GT((b - c).norm(), 0.05) << "order " << order;
      }
    }
  }
}

TEST(HemisphereProjector, SmallestEigenvectorAndCutoff) {
  const int order = 5, n = sh_count(order);
  const Eigen::MatrixXd a = sh_zone_gram_closed_form(order, 0.0, 1.0);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(a);
  const Eigen::VectorXd v = eig.eigenvectors().col(0);
  const double lmin = eig.eigenvalues()[0];
  const Eigen::VectorXd b = a * v;  // a signal that almost vanishes on H

  const HemisphereProjector exact(order);
  EXPECT_NEAR(exact.smallest_kept_eigenvalue(), lmin, 1e-15);
  const Eigen::VectorXd got = exact.solve(b);
  // b carries the rounding of a * v, about n eps; the solve divides it by lambda_min.
  EXPECT_LT((got - v).norm(), 64 * n * kEps / lmin);

  // With a cutoff above lambda_min / lambda_max the direction is left out: the result is the
  // minimum-norm solution, and its error on H is exactly that direction's part, sqrt(lambda_min).
  const HemisphereProjector cut(order, {.relative_cutoff = 1e-4});
  EXPECT_EQ(cut.cut_directions(), 1);
  EXPECT_NEAR(cut.largest_cut_eigenvalue(), lmin, 1e-15);
  const Eigen::VectorXd got_cut = cut.solve(b);
  EXPECT_LT(got_cut.norm(), 64 * n * kEps / cut.smallest_kept_eigenvalue());
  EXPECT_NEAR(a_norm(a, got_cut - v), std::sqrt(lmin), 1e-9 * std::sqrt(lmin));
}

TEST(HemisphereProjector, NoisyProjectionStaysBounded) {
  const int order = 5, n = sh_count(order);
  const Eigen::MatrixXd a = sh_zone_gram_closed_form(order, 0.0, 1.0);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(a);
  const Eigen::VectorXd vmin = eig.eigenvectors().col(0);
  std::mt19937_64 rng(kSeed + 1);
  SCOPED_TRACE(testing::Message() << "seed " << kSeed + 1);
  const Eigen::VectorXd c = random_unit(n, rng);
  const double eps_noise = 1e-6;
  const double tau = 1e-4;
  const HemisphereProjector exact(order);
  const HemisphereProjector cut(order, {.relative_cutoff = tau});
  for (int trial = 0; trial < 4; ++trial) {
    // Noise along the worst direction first, then random directions.
    const Eigen::VectorXd eta = trial == 0 ? vmin : random_unit(n, rng);
    const Eigen::VectorXd b = a * c + eps_noise * eta;
    // Without a cutoff the noise is amplified by up to 1 / lambda_min (exactly along vmin).
    const Eigen::VectorXd plain = exact.solve(b);
    EXPECT_LE((plain - c).norm(), eps_noise / exact.smallest_kept_eigenvalue() * (1 + 1e-6));
    if (trial == 0) {
      EXPECT_NEAR((plain - c).norm(), eps_noise / exact.smallest_kept_eigenvalue(),
                  1e-6 * eps_noise / exact.smallest_kept_eigenvalue());
    }
    // With it, the guarantee of the header: bounded coefficients and a bounded error on H.
    const Eigen::VectorXd got = cut.solve(b);
    const double lk = cut.smallest_kept_eigenvalue(), lc = cut.largest_cut_eigenvalue();
    EXPECT_LE(got.norm(), b.norm() / lk);
    EXPECT_LE(got.norm(), c.norm() + eps_noise / lk + 1e-12);
    EXPECT_LE(a_norm(a, got - c), std::sqrt(lc) * c.norm() + eps_noise / std::sqrt(lk) + 1e-12);
    // The identity behind it, term by term in A's eigenbasis.
    double want2 = 0.0;
    for (int j = 0; j < n; ++j) {
      const double lj = eig.eigenvalues()[j];
      const Eigen::VectorXd vj = eig.eigenvectors().col(j);
      want2 += lj <= tau * cut.largest_eigenvalue() ? lj * std::pow(vj.dot(c), 2)
                                                    : std::pow(vj.dot(eps_noise * eta), 2) / lj;
    }
    EXPECT_NEAR(std::pow(a_norm(a, got - c), 2), want2, 1e-9 * want2);
  }
}

TEST(HemisphereProjector, DroppedBasisFunctionCostsExactlyItsDiscardError) {
  const int order = 5, n = sh_count(order), i = sh_index(1, 0);
  const Eigen::MatrixXd a = sh_zone_gram_closed_form(order, 0.0, 1.0);
  const HemisphereProjector drop(order, {.dropped_index = i});
  const Eigen::VectorXd lambda = hemisphere_gram_eigenvalues(order);
  // Interlacing: the reduced matrix's smallest eigenvalue lies between A's two smallest.
  EXPECT_GE(drop.smallest_kept_eigenvalue(), lambda[n - 1]);
  EXPECT_LE(drop.smallest_kept_eigenvalue(), lambda[n - 2] * (1 + 1e-12));
  EXPECT_GT(drop.smallest_kept_eigenvalue(), 10 * lambda[n - 1]);
  const double e = hemisphere_discard_errors(order)[i];
  std::mt19937_64 rng(kSeed + 2);
  SCOPED_TRACE(testing::Message() << "seed " << kSeed + 2);
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd c = random_unit(n, rng);
    const Eigen::VectorXd got = drop.solve(a * c);
    EXPECT_EQ(got[i], 0.0);
    const double err2 = std::pow(a_norm(a, got - c), 2);
    EXPECT_NEAR(err2, c[i] * c[i] * e, 1e-8 * e);
  }
}

TEST(HemisphereProjector, RejectsBadParameters) {
  EXPECT_THROW(HemisphereProjector(0), ParameterError);
  EXPECT_THROW(HemisphereProjector(kMaxShOrder + 1), ParameterError);
  EXPECT_THROW(HemisphereProjector(3, {.relative_cutoff = -1.0}), ParameterError);
  EXPECT_THROW(HemisphereProjector(3, {.relative_cutoff = 1.0}), ParameterError);
  EXPECT_THROW(HemisphereProjector(3, {.dropped_index = 9}), ParameterError);
  EXPECT_THROW(HemisphereProjector(3).solve(Eigen::VectorXd::Zero(4)), ParameterError);
  EXPECT_THROW(hemisphere_gram(0), ParameterError);
  EXPECT_THROW(sh_zone_gram(3, 0.5, 0.5), ParameterError);
  EXPECT_THROW(hemisphere_projection_error_matrix(HemisphereProjectionKind::kOddReflection, 5, 4),
               ParameterError);
  EXPECT_THROW(analyse_hemisphere_projection(5, {.odd_order = 4}), ParameterError);
  EXPECT_THROW(analyse_hemisphere_projection(5, {.even_order = 11}), ParameterError);
}

TEST(HemisphereError, ReflectionScaleFollowsTheParityOfShEval) {
  std::mt19937_64 rng(kSeed + 3);
  const int order = 8;
  const Eigen::VectorXd odd = reflection_scale(HemisphereProjectionKind::kOddReflection, order);
  const Eigen::VectorXd even = reflection_scale(HemisphereProjectionKind::kEvenReflection, order);
  for (int t = 0; t < 20; ++t) {
    const Eigen::VectorXd r = random_unit(3, rng);
    const Vec3d d{r[0], r[1], r[2]}, mirrored{r[0], r[1], -r[2]};
    std::array<double, 64> y{}, ym{};
    sh_eval(order, d, y);
    sh_eval(order, mirrored, ym);
    for (int i = 0; i < 64; ++i) {
      // odd in z (y(x, y, -z) = -y) exactly where odd reflection keeps 2 b_i.
      const double parity = odd[i] == 2.0 ? -1.0 : 1.0;
      EXPECT_NEAR(ym[i], parity * y[i], 1e-13) << i;
      EXPECT_EQ(odd[i] + even[i], 2.0);
    }
  }
  // The paper's counts: 28 odd of 64 at order 8, 28 even of 49 at order 7, 15 even at order 5.
  EXPECT_EQ(
      hemisphere_projection_error(HemisphereProjectionKind::kOddReflection, 5, 8).coefficients, 28);
  EXPECT_EQ(
      hemisphere_projection_error(HemisphereProjectionKind::kEvenReflection, 5, 7).coefficients,
      28);
  EXPECT_EQ(
      hemisphere_projection_error(HemisphereProjectionKind::kEvenReflection, 5, 5).coefficients,
      15);
  EXPECT_EQ(
      hemisphere_projection_error(HemisphereProjectionKind::kZeroHemisphere, 5, 5).coefficients,
      25);
}

// Explicit computation of the projections' errors, independent of A and Q: f on H from c, its
// extension below the horizon (zero, odd or even), the extension's SH projection by a Gauss rule
// on each half of the sphere (each half's integrand is a polynomial restriction, so the rule is
// exact), then the squared error over H by the upper rule. One column per signal.
struct ExplicitErrors {
  int signal_order, projection_order;
  std::vector<SphereQuadratureNode> upper;
  Eigen::MatrixXd y_upper, y_lower;  // at the upper nodes and at their mirror images
  Eigen::VectorXd w;

  ExplicitErrors(int n_order, int m_order)
      : signal_order(n_order),
        projection_order(m_order),
        upper(zone_gauss_rule(0.0, 1.0, n_order + m_order, 2 * (n_order + m_order))),
        y_upper(sh_rows(m_order, upper)),
        y_lower(sh_rows(m_order, upper, /*mirror=*/true)),
        w(weights(upper)) {}

  Eigen::VectorXd operator()(HemisphereProjectionKind kind, const Eigen::MatrixXd& c) const {
    const int n = sh_count(signal_order);
    const Eigen::MatrixXd f = y_upper.leftCols(n) * c;  // f at the upper nodes
    // The extension at a mirrored node: 0, -f or +f of the node it mirrors.
    const double sign = kind == HemisphereProjectionKind::kZeroHemisphere  ? 0.0
                        : kind == HemisphereProjectionKind::kOddReflection ? -1.0
                                                                           : 1.0;
    const Eigen::MatrixXd wf = w.asDiagonal() * f;
    const Eigen::MatrixXd p = y_upper.transpose() * wf + sign * (y_lower.transpose() * wf);
    const Eigen::MatrixXd r = y_upper * p - f;
    return (w.asDiagonal() * r.cwiseAbs2()).colwise().sum().transpose();
  }
};

struct Case {
  HemisphereProjectionKind kind;
  int projection_order;
};
constexpr int kSignalOrder = 5;
const Case kCases[] = {{HemisphereProjectionKind::kZeroHemisphere, 5},
                       {HemisphereProjectionKind::kOddReflection, 8},
                       {HemisphereProjectionKind::kEvenReflection, 7},
                       {HemisphereProjectionKind::kEvenReflection, 5}};

TEST(HemisphereError, QuadraticFormMatchesExplicitQuadrature) {
  const int n = sh_count(kSignalOrder);
  std::mt19937_64 rng(kSeed + 4);
  SCOPED_TRACE(testing::Message() << "seed " << kSeed + 4);
  Eigen::MatrixXd c(n, 20);
  for (int s = 0; s < c.cols(); ++s) c.col(s) = random_unit(n, rng);
  for (const Case& k : kCases) {
    SCOPED_TRACE(testing::Message() << to_string(k.kind) << " at order " << k.projection_order);
    const Eigen::MatrixXd q =
        hemisphere_projection_error_matrix(k.kind, kSignalOrder, k.projection_order);
    const ExplicitErrors explicit_errors(kSignalOrder, k.projection_order);
    const Eigen::VectorXd got = explicit_errors(k.kind, c);
    for (int s = 0; s < c.cols(); ++s) {
      EXPECT_NEAR(got[s], c.col(s).dot(q * c.col(s)), 1e-13) << "signal " << s;
      EXPECT_GT(got[s], 1e-6);  // none of the three projections is exact on H
    }
    // The worst case is attained by Q's top eigenvector.
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(q);
    const HemisphereProjectionError e =
        hemisphere_projection_error(k.kind, kSignalOrder, k.projection_order);
    EXPECT_NEAR(explicit_errors(k.kind, eig.eigenvectors().col(n - 1))[0], e.worst, 1e-13);
  }
}

TEST(HemisphereError, WorstAndAverageBoundMonteCarlo) {
  const int n = sh_count(kSignalOrder), samples = 2000;
  std::mt19937_64 rng(kSeed + 5);
  SCOPED_TRACE(testing::Message() << "seed " << kSeed + 5);
  Eigen::MatrixXd c(n, samples);
  for (int s = 0; s < samples; ++s) c.col(s) = random_unit(n, rng);
  for (const Case& k : kCases) {
    SCOPED_TRACE(testing::Message() << to_string(k.kind) << " at order " << k.projection_order);
    const HemisphereProjectionError e =
        hemisphere_projection_error(k.kind, kSignalOrder, k.projection_order);
    const Eigen::VectorXd got = ExplicitErrors(kSignalOrder, k.projection_order)(k.kind, c);
    EXPECT_LE(got.maxCoeff(), e.worst + 1e-12);
    EXPECT_GT(got.maxCoeff(), 0.5 * e.average);
    // c^T Q c = sum_j mu_j u_j^2 with u uniform on the sphere: mean trace / n, variance
    // 2 / (n + 2) (mean(mu^2) - mean(mu)^2). The sample mean is within 5 standard errors.
    const Eigen::MatrixXd q =
        hemisphere_projection_error_matrix(k.kind, kSignalOrder, k.projection_order);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(q, Eigen::EigenvaluesOnly);
    const Eigen::VectorXd mu = eig.eigenvalues();
    EXPECT_NEAR(mu.maxCoeff(), e.worst, 1e-14);
    EXPECT_NEAR(mu.mean(), e.average, 1e-14);
    const double variance = 2.0 / (n + 2) * (mu.squaredNorm() / n - mu.mean() * mu.mean());
    EXPECT_NEAR(got.mean(), e.average, 5.0 * std::sqrt(variance / samples));
    EXPECT_NEAR(e.worst_rms_percent(), 100.0 * std::sqrt(e.worst), 1e-12);
  }
}

TEST(HemisphereError, ZeroHemisphereErrorFollowsTheEigenvaluesOfA) {
  // Q1 = (A - I) A (A - I) shares A's eigenvectors, with eigenvalues lambda (1 - lambda)^2.
  for (int order = 1; order <= 6; ++order) {
    const Eigen::VectorXd lambda = hemisphere_gram_eigenvalues(order);
    const Eigen::ArrayXd mu = lambda.array() * (1.0 - lambda.array()).square();
    const HemisphereProjectionError e =
        hemisphere_projection_error(HemisphereProjectionKind::kZeroHemisphere, order, order);
    EXPECT_NEAR(e.worst, mu.maxCoeff(), 1e-14) << order;
    EXPECT_NEAR(e.average, mu.mean(), 1e-14) << order;
  }
}

TEST(HemisphereError, OrderFiveAgreesWithThePapersRanking) {
  const HemisphereAnalysis a = analyse_hemisphere_projection(5);
  ASSERT_EQ(a.projections.size(), 4u);
  const HemisphereProjectionError &zero = a.projections[0], &odd = a.projections[1],
                                  &even = a.projections[2], &even5 = a.projections[3];
  EXPECT_EQ(odd.projection_order, 8);
  EXPECT_EQ(even.projection_order, 7);
  EXPECT_EQ(even5.projection_order, 5);
  // Even reflection best, zero-hemisphere next, odd reflection worst, in both measures; even
  // reflection at order 5 beats zero-hemisphere on average with 15 coefficients instead of 25.
  EXPECT_LT(even.worst, zero.worst);
  EXPECT_LT(zero.worst, odd.worst);
  EXPECT_LT(even.average, zero.average);
  EXPECT_LT(zero.average, odd.average);
  EXPECT_LT(even5.average, zero.average);
  EXPECT_EQ(a.most_redundant, sh_index(1, 0));
  // Defaults are raised to the signal order above the paper's orders.
  const HemisphereAnalysis a9 = analyse_hemisphere_projection(9);
  EXPECT_EQ(a9.projections[1].projection_order, 9);
  EXPECT_EQ(a9.projections[2].projection_order, 9);
}

}  // namespace
}  // namespace prt
