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
#include "prtlab/opencl/cl_context.h"
#include "prtlab/render/device_material_eval.h"
#include "prtlab/render/factored_material.h"
#include "prtlab/storage/archive.h"
#include "support/material_queries.h"
#include "support/temp_dir.h"

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

TEST(Hf, GaussNewtonRefinementLowersTheLinearErrorOfTheLogFit) {
  BtfParams bp;
  bp.resolution = 3;
  bp.view_side = 4;
  bp.light_side = 4;
  bp.supersampling = 1;
  bp.geometry_grid = 24;
  const auto btf = std::make_shared<const Btf>(generate_btf(make_btf_material("weave", 24), bp));
  // On one ABRDF channel: the objective the steps are accepted on never grows.
  HomomorphicOptions o;
  o.light_side = 4;
  o.view_side = 4;
  o.half_side = 6;
  const HomomorphicFactorization hf(o);
  std::vector<double> f(static_cast<std::size_t>(hf.light_count()) * hf.view_count()), y(f.size()),
      x(static_cast<std::size_t>(hf.light_count() + hf.half_count() + hf.view_count()));
  for (std::size_t s = 0; s < f.size(); ++s) f[s] = btf->data()[btf->offset(4, 0, 0) + s * 3];
  const double peak = *std::max_element(f.begin(), f.end());
  for (std::size_t s = 0; s < f.size(); ++s) y[s] = std::log(std::max(f[s], o.floor * peak));
  hf.solve_log(y, x);
  const double before = hf.linear_objective(f, x), after = hf.refine_linear(f, x, 10);
  EXPECT_LE(after, before);
  EXPECT_EQ(after, hf.linear_objective(f, x));
  // Through the material: the refined factors have a lower error against the BTF.
  std::map<std::string, std::string> params = {
      {"half_side", "6"}, {"clusters", "0"}, {"quantize", "false"}, {"refit_scale", "false"}};
  const double log_fit = material_error(*compress_material("hf", params, btf), *btf).relative_l2;
  params["refine"] = "10";
  const double refined = material_error(*compress_material("hf", params, btf), *btf).relative_l2;
  EXPECT_LT(refined, 0.9 * log_fit) << "log fit " << log_fit << ", refined " << refined;
}

// ---- the material's halfway interpolation ----

// A BTF whose every texel channel is exactly P(d) exp((W q)_s) R(e), W the halfway weights
// shading uses, with a steep, smooth q (a bowl spanning `depth` in the logarithm, so Q spans
// e^depth) and smooth P and R; the log factors x* = (log P, q, log R) have mean-zero q and log R,
// as the fit's two mean rows ask. `laplacian_norm` receives the largest, over texel channels,
// ||L x*||_2 with L the fit's unweighted 5-point Laplacian of each factor.
struct LogProduct {
  Btf btf;
  double laplacian_norm = 0;
};

double laplacian_norm(std::span<const double> x, int side) {
  double sum = 0;
  for (int y = 0; y < side; ++y)
    for (int i = 0; i < side; ++i) {
      double row = 0;
      int n = 0;
      for (const auto& [dx, dy] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
        const int xx = i + dx, yy = y + dy;
        if (xx < 0 || yy < 0 || xx >= side || yy >= side) continue;
        row -= x[static_cast<std::size_t>(yy * side + xx)];
        ++n;
      }
      row += n * x[static_cast<std::size_t>(y * side + i)];
      sum += row * row;
    }
  return sum;
}

LogProduct log_linear_btf(int ls, int vs, int hs, double depth) {
  const int res = 2, m = ls * ls, v = vs * vs, h = hs * hs;
  const auto w = halfway_weights(ls, vs, hs);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  LogProduct out;
  std::vector<float> rgb(static_cast<std::size_t>(res * res) * m * v * 3);
  for (int t = 0; t < res * res; ++t)
    for (int c = 0; c < 3; ++c) {
      std::vector<double> lp(m), q(h), lr(v);
      const double cx = 0.5 * u(rng), cy = 0.5 * u(rng), a = 0.3 * u(rng), b = 0.3 * u(rng);
      for (int i = 0; i < h; ++i) {
        const double x = 2.0 * ((i % hs) + 0.5) / hs - 1.0 - cx,
                     y = 2.0 * ((i / hs) + 0.5) / hs - 1.0 - cy;
        q[i] = -depth * 0.5 * (x * x + y * y);
      }
      for (int j = 0; j < m; ++j) lp[j] = a * (j % ls) / ls;
      for (int e = 0; e < v; ++e) lr[e] = b * (e / vs) / vs;
      const auto centre = [](std::vector<double>& x) {
        double mean = 0;
        for (double y : x) mean += y / static_cast<double>(x.size());
        for (double& y : x) y -= mean;
        return mean;
      };
      const double shift = centre(q) + centre(lr);
      for (double& y : lp) y += shift - 1.0;
      const double norm =
          std::sqrt(laplacian_norm(lp, ls) + laplacian_norm(q, hs) + laplacian_norm(lr, vs));
      out.laplacian_norm = std::max(out.laplacian_norm, norm);
      const Eigen::VectorXd q_io = w * Eigen::Map<const Eigen::VectorXd>(q.data(), h);
      for (int s = 0; s < m * v; ++s)
        rgb[(static_cast<std::size_t>(t) * m * v + s) * 3 + c] =
            static_cast<float>(std::exp(lp[s % m] + q_io[s] + lr[s / m]));
    }
  out.btf = Btf("log-linear", res, vs, ls, std::move(rgb));
  return out;
}

// Largest relative deviation of the material from the BTF over every sample, through
// reflectance() and, at texel centres and the view grid's directions, through eval_lights().
struct Deviation {
  double reflectance = 0, eval_lights = 0;
};

Deviation deviation(const CompressedMaterial& mat, const Btf& btf) {
  Deviation d;
  const std::vector<Vec3> views = light_directions_f(btf.view_side());
  std::vector<Rgb> out(static_cast<std::size_t>(btf.light_count()));
  for (int t = 0; t < btf.texel_count(); ++t) {
    const int res = btf.resolution();
    const Vec2 uv((static_cast<float>(t % res) + 0.5f) / static_cast<float>(res),
                  (static_cast<float>(t / res) + 0.5f) / static_cast<float>(res));
    for (int v = 0; v < btf.view_count(); ++v) {
      mat.eval_lights(uv, views[static_cast<std::size_t>(v)], out, TexelFilter::kNearest);
      for (int j = 0; j < btf.light_count(); ++j) {
        const Rgb f = btf.value(t, v, j), g = mat.reflectance(t, v, j);
        for (int c = 0; c < 3; ++c) {
          d.reflectance = std::max(d.reflectance, std::abs(g[c] / f[c] - 1.0));
          d.eval_lights =
              std::max(d.eval_lights, std::abs(out[static_cast<std::size_t>(j)][c] / f[c] - 1.0));
        }
      }
    }
  }
  return d;
}

std::unique_ptr<FactoredMaterial> with_interpolation(const CompressedMaterial& m,
                                                     HalfwayInterpolation mode) {
  FactoredMaterial::State st = dynamic_cast<const FactoredMaterial&>(m).state();
  st.interpolation = mode;
  return std::make_unique<FactoredMaterial>(std::move(st));
}

const std::map<std::string, std::string> kExactParams = {
    {"half_side", "6"}, {"lambda", "0.0001"},  {"floor", "1e-12"},
    {"clusters", "0"},  {"quantize", "false"}, {"refit_scale", "false"}};

TEST(Hf, TheMaterialReproducesAnExactLogLinearProductThroughItsOwnShading) {
  // The fit minimises ||A x - y||^2 + lambda^2 ||L x||^2 (+ the mean rows, which x* satisfies),
  // so at its minimum ||A x - y||^2 <= lambda^2 ||L x*||^2: every sample's log model is within
  // delta = lambda ||L x*||_2 of log f, and the model itself within e^delta - 1 relative. Float
  // factors and float shading add a few 1e-7 per operation: 1e-5 on top.
  const double lambda = 1e-4;
  const LogProduct lp = log_linear_btf(5, 4, 6, 8.0);
  const double bound = std::expm1(lambda * lp.laplacian_norm) + 1e-5;
  ASSERT_LT(bound, 5e-3) << "the product is too rough for the bound to mean anything";
  const auto btf = std::make_shared<const Btf>(lp.btf);
  const auto m = compress_material("hf", kExactParams, btf);
  ASSERT_EQ(dynamic_cast<const FactoredMaterial&>(*m).state().interpolation,
            HalfwayInterpolation::kGeometric);
  const Deviation d = deviation(*m, *btf);
  EXPECT_LT(d.reflectance, bound);
  EXPECT_LT(d.eval_lights, bound);
  EXPECT_LT(m->declared_error_bound(), bound);
  // The same factors read with linear interpolation (what shading did before the mode existed)
  // overshoot wherever a sample sits between halfway cells of different Q (Jensen): the test
  // tells the two apart by far more than its bound.
  const Deviation linear = deviation(*with_interpolation(*m, HalfwayInterpolation::kLinear), *btf);
  EXPECT_GT(linear.reflectance, 20 * bound);
  EXPECT_GT(linear.eval_lights, 20 * bound);
}

TEST(Hf, GeometricInterpolationOnTheDeviceMatchesTheCppReference) {
  ClContext* ctx = default_context();
  if (ctx == nullptr)
    GTEST_SKIP() << "no OpenCL device on this machine: the device path is not tested here";
  const auto btf = std::make_shared<const Btf>(log_linear_btf(5, 4, 6, 8.0).btf);
  const auto fitted = compress_material("hf", kExactParams, btf);
  // Parts with each interpolation (the part table carries it), and one whose Q has zeros (an
  // 8-bit code 0: read as FLT_MIN in the logarithm).
  FactoredMaterial::State zeros = dynamic_cast<const FactoredMaterial&>(*fitted).state();
  for (std::size_t i = 0; i < zeros.codebook_q.size(); i += 7) zeros.codebook_q[i] = 0.0f;
  const auto linear = with_interpolation(*fitted, HalfwayInterpolation::kLinear);
  const FactoredMaterial holes(std::move(zeros));
  const std::vector<const CompressedMaterial*> parts = {fitted.get(), linear.get(), &holes};
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> uv(-0.5f, 1.5f), xy(-1.0f, 1.0f);
  std::vector<MaterialQuery> qs;
  for (int i = 0; i < 60; ++i) {
    Vec3 e(xy(rng), xy(rng), std::abs(xy(rng)) + 0.05f);
    qs.push_back({i % 3, Vec2(uv(rng), uv(rng)), glm::normalize(e)});
  }
  // Logarithms of Q down to e^-8 and float exp on each side: 1e-5 of the vector's peak.
  std::string where;
  EXPECT_LE(testing::device_vs_cpp_eval_lights(*ctx, parts, qs, btf->light_count(), &where), 1e-5)
      << where;
}

TEST(Hf, TheInterpolationSurvivesSaveAndLoadAndAnUnknownOneIsRefused) {
  const auto btf = std::make_shared<const Btf>(log_linear_btf(3, 3, 4, 2.0).btf);
  const auto m =
      compress_material("hf", {{"half_side", "4"}, {"clusters", "2"}, {"quantize", "true"}}, btf);
  const testing::TempDir dir("hf");
  save_material(*m, dir / "hf.prtm");
  const auto loaded = load_material(dir / "hf.prtm");
  EXPECT_EQ(dynamic_cast<const FactoredMaterial&>(*loaded).state().interpolation,
            HalfwayInterpolation::kGeometric);
  for (int t = 0; t < btf->texel_count(); ++t)
    for (int v = 0; v < btf->view_count(); ++v)
      for (int j = 0; j < btf->light_count(); ++j) {
        const Rgb a = loaded->reflectance(t, v, j), b = m->reflectance(t, v, j);
        ASSERT_EQ(std::memcmp(&a, &b, sizeof(Rgb)), 0);
      }
  // The archive as save_material writes it, with the state's metadata edited.
  const auto write = [&](const std::filesystem::path& file, const auto& edit) {
    ArchiveWriter w("compressed-material", 1);
    w.add_meta("backend", m->backend());
    m->save(w);
    edit(w.meta().at("factored"));
    w.write(file);
  };
  write(dir / "cubic.prtm", [](nlohmann::json& j) { j["halfway_interpolation"] = "cubic"; });
  try {
    (void)load_material(dir / "cubic.prtm");
    ADD_FAILURE() << "an unknown halfway interpolation was accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("cubic.prtm"), std::string::npos) << what;
    EXPECT_NE(what.find("halfway interpolation 'cubic'"), std::string::npos) << what;
  }
  // A state of version 1 (before the interpolation was stored) is linear.
  write(dir / "v1.prtm", [](nlohmann::json& j) {
    j["format_version"] = 1;
    j.erase("halfway_interpolation");
  });
  EXPECT_EQ(
      dynamic_cast<const FactoredMaterial&>(*load_material(dir / "v1.prtm")).state().interpolation,
      HalfwayInterpolation::kLinear);
  // A version this build does not know is refused.
  write(dir / "v9.prtm", [](nlohmann::json& j) { j["format_version"] = 9; });
  EXPECT_THROW((void)load_material(dir / "v9.prtm"), InputError);
}

}  // namespace
}  // namespace prt::hf
