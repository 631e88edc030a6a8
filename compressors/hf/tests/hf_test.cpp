// Material hf (homomorphic factorisation, McCool et al. 2001 as Suykens et al. 2003 use it): the
// log system recovers an exact log-linear product of three factors within its regularisation
// bias (the bias shrinks with lambda); shadowed zeros are floored, not turned into -inf; one
// factorised system serves every texel, and parallel compression equals serial. The material
// conformance suite covers the OpenCL evaluation against the C++ one, save/load and the declared
// error.
#include "hf/hf.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "prtlab/btf/btf_generator.h"
#include "prtlab/btf/btf_materials.h"
#include "prtlab/btf/halfway_parameterization.h"
#include "prtlab/compress/material_error.h"
#include "prtlab/compress/material_registry.h"

namespace prt::hf {
namespace {

HomomorphicOptions options(double lambda) {
  HomomorphicOptions o;
  o.light_side = 5;
  o.view_side = 4;
  o.half_side = 6;
  o.lambda = lambda;
  return o;
}

// y_s = p_j + (W q)_s + r_v: the model HF fits, exactly, with smooth random factors (a
// Laplacian regulariser biases a rough field more than a smooth one; either is recovered as
// lambda -> 0).
std::vector<double> log_product(const HomomorphicOptions& o, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int m = o.light_side * o.light_side, v = o.view_side * o.view_side,
            h = o.half_side * o.half_side;
  std::vector<double> p(m), q(h), r(v);
  const double a = u(rng), b = u(rng), c = u(rng);
  for (int j = 0; j < m; ++j) p[j] = a * (j % o.light_side) / o.light_side + 0.1 * u(rng);
  for (int i = 0; i < h; ++i) q[i] = b * (i / o.half_side) / o.half_side + 0.1 * u(rng);
  for (int e = 0; e < v; ++e) r[e] = c * (e % o.view_side) / o.view_side + 0.1 * u(rng);
  const auto w = halfway_weights(o.light_side, o.view_side, o.half_side);
  const Eigen::VectorXd q_io = w * Eigen::Map<const Eigen::VectorXd>(q.data(), h);
  std::vector<double> y(static_cast<std::size_t>(m) * v);
  for (int s = 0; s < m * v; ++s) y[s] = p[s % m] + q_io[s] + r[s / m];
  return y;
}

// Largest |model - y| over the samples after the log solve.
double log_residual(double lambda, const std::vector<double>& y) {
  const HomomorphicOptions o = options(lambda);
  const HomomorphicFactorization hf(o);
  const int m = hf.light_count(), h = hf.half_count(), v = hf.view_count();
  std::vector<double> x(static_cast<std::size_t>(m + h + v));
  hf.solve_log(y, x);
  const auto w = halfway_weights(o.light_side, o.view_side, o.half_side);
  const Eigen::VectorXd q_io = w * Eigen::Map<const Eigen::VectorXd>(x.data() + m, h);
  double err = 0;
  for (int s = 0; s < m * v; ++s)
    err = std::max(err, std::abs(x[s % m] + q_io[s] + x[m + h + s / m] - y[s]));
  return err;
}

TEST(Hf, AnExactLogProductIsRecoveredWithinTheRegularisationBias) {
  const std::vector<double> y = log_product(options(1), 11);
  const double tiny = log_residual(1e-7, y), small = log_residual(1e-3, y),
               large = log_residual(1.0, y);
  EXPECT_LT(tiny, 1e-6);
  EXPECT_LT(tiny, small);
  EXPECT_LT(small, large);
  EXPECT_GT(large, 1e-3) << "the test must see the regulariser's bias at lambda = 1";
}

TEST(Hf, FactorsAreFiniteAndPositiveWithShadowedZeros) {
  const HomomorphicFactorization hf(options(0.1));
  std::vector<double> f(static_cast<std::size_t>(hf.light_count()) * hf.view_count(), 0.5);
  for (std::size_t s = 0; s < f.size(); s += 3) f[s] = 0.0;
  std::vector<double> p(hf.light_count()), q(hf.half_count()), r(hf.view_count());
  hf.factor(f, p, q, r);
  for (const auto* v : {&p, &q, &r})
    for (double x : *v) EXPECT_TRUE(std::isfinite(x) && x > 0) << x;
  // All-zero ABRDF channels have zero factors (no logarithm to take).
  std::fill(f.begin(), f.end(), 0.0);
  hf.factor(f, p, q, r);
  EXPECT_EQ(*std::max_element(p.begin(), p.end()), 0.0);
}

TEST(Hf, OneFactorisedSystemGivesEachTexelTheSolutionAFreshSystemGives) {
  const HomomorphicFactorization shared(options(0.1));
  const std::vector<double> y1 = log_product(options(1), 1), y2 = log_product(options(1), 2);
  const std::size_t n =
      static_cast<std::size_t>(shared.light_count() + shared.half_count() + shared.view_count());
  std::vector<double> a(n), b(n), c(n);
  shared.solve_log(y1, a);
  shared.solve_log(y2, b);
  HomomorphicFactorization(options(0.1)).solve_log(y2, c);
  EXPECT_EQ(b, c);  // the first solve left no state behind
  EXPECT_NE(a, b);
}

TEST(Hf, ParallelCompressionEqualsSerialBitForBit) {
  // factor() runs concurrently over texels; the result must not depend on the thread count.
  BtfParams bp;
  bp.resolution = 4;
  bp.view_side = 3;
  bp.light_side = 3;
  bp.supersampling = 1;
  bp.geometry_grid = 16;
  const auto btf = std::make_shared<const Btf>(generate_btf(make_btf_material("bumps", 16), bp));
  for (const char* backend : {"hf", "cmf"}) {
    const auto parallel = compress_material(backend, {{"half_side", "5"}}, btf);
    std::shared_ptr<const CompressedMaterial> serial;
    {
      const tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
      serial = compress_material(backend, {{"half_side", "5"}}, btf);
    }
    for (int t = 0; t < btf->texel_count(); ++t)
      for (int v = 0; v < btf->view_count(); ++v)
        for (int j = 0; j < btf->light_count(); ++j) {
          const Rgb a = parallel->reflectance(t, v, j), b = serial->reflectance(t, v, j);
          ASSERT_EQ(std::memcmp(&a, &b, sizeof(Rgb)), 0) << backend << " texel " << t;
        }
  }
}

}  // namespace
}  // namespace prt::hf
