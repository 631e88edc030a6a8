// Material cmf (chained matrix factorisation, Suykens et al. 2003): the chain recovers an exact
// product of three factors (its last step exactly for a rank-1 residue, the whole product by
// the alternating refinement the paper does not have) and, with two terms, a sum of two
// products that one term cannot fit; the fit never gets worse with more terms or more
// refinement; clustering with as many clusters as texels is lossless before quantisation;
// 8-bit storage stays within the bound its steps imply; every ABRDF of a texel-varying product
// BTF comes back through the material; terms evaluate on the device as in C++ and survive
// save/load (an older state reads as one term); step 1's resampling reads the incident
// direction on the light grid and the exitant one on the view grid (an ABRDF of the light alone
// gives the halfway means of the light function at the GSHD incident directions; a light/view
// swap is invisible to Q by the mirror symmetry of the GSHD difference grid). The material
// conformance suite covers the OpenCL evaluation against the C++ one, save/load and the
// declared error.
#include "cmf/cmf.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

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
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/storage/archive.h"
#include "support/material_queries.h"
#include "support/temp_dir.h"

namespace prt::cmf {
namespace {

struct Product {
  std::vector<double> p, q, r, f;
};

// f_s = P_j (W q)_s R_v with random positive factors (q constant when `flat_q`).
Product random_product(int light_side, int view_side, int half_side, unsigned seed, bool flat_q) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.2, 1.0);
  const int m = light_side * light_side, v = view_side * view_side, h = half_side * half_side;
  Product x;
  for (int j = 0; j < m; ++j) x.p.push_back(u(rng));
  for (int a = 0; a < h; ++a) x.q.push_back(flat_q ? 0.5 : u(rng));
  for (int e = 0; e < v; ++e) x.r.push_back(u(rng));
  const auto w = halfway_weights(light_side, view_side, half_side);
  const Eigen::VectorXd q_io = w * Eigen::Map<const Eigen::VectorXd>(x.q.data(), h);
  for (int s = 0; s < m * v; ++s) x.f.push_back(x.p[s % m] * q_io[s] * x.r[s / m]);
  return x;
}

double product_error(const ChainedFactorization& c, const Product& x) {
  const int m = c.light_count(), v = c.view_count(), h = c.half_count();
  std::vector<double> p(m), q(h), r(v);
  c.factor(x.f, p, q, r);
  const auto w =
      halfway_weights(c.options().light_side, c.options().view_side, c.options().half_side);
  const Eigen::VectorXd q_io = w * Eigen::Map<const Eigen::VectorXd>(q.data(), h);
  double err = 0, peak = 0;
  for (int s = 0; s < m * v; ++s) {
    err = std::max(err, std::abs(p[s % m] * q_io[s] * r[s / m] - x.f[s]));
    peak = std::max(peak, x.f[s]);
  }
  return err / peak;
}

ChainOptions options(int refine, HalfwayRule rule = HalfwayRule::kSvd) {
  ChainOptions o;
  o.light_side = 5;
  o.view_side = 4;
  o.half_side = 6;
  o.diff_side = 6;
  o.halfway = rule;
  o.refine = refine;
  return o;
}

TEST(Cmf, TheLastStepRecoversARankOneResidueExactly) {
  // Step 3's rank-1 fit of an exact outer product P R^T (the residue of a BTF whose halfway
  // factor step 2 got right) returns it to rounding.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.2, 1.0);
  const int rows = 25, cols = 16;
  std::vector<double> a(rows * cols), x(rows), y(cols), p(rows), r(cols);
  for (double& v : x) v = u(rng);
  for (double& v : y) v = u(rng);
  for (int c = 0; c < cols; ++c)
    for (int i = 0; i < rows; ++i) a[static_cast<std::size_t>(c) * rows + i] = x[i] * y[c];
  rank_one(a, rows, cols, p, r);
  double err = 0;
  for (int c = 0; c < cols; ++c)
    for (int i = 0; i < rows; ++i) err = std::max(err, std::abs(p[i] * r[c] - x[i] * y[c]));
  EXPECT_LT(err, 1e-14);
}

TEST(Cmf, RefinementRecoversAGeneralProductOfThreeFactors) {
  // Step 2's averages of a product mix P and R into Q's estimate, so the paper's single pass
  // leaves an error; the alternating refinement converges (slowly: its sweeps zig-zag along
  // the coupled factors) to the product.
  const Product x = random_product(5, 4, 6, 7, false);
  const double once = product_error(ChainedFactorization(options(0)), x);
  const double refined = product_error(ChainedFactorization(options(1000)), x);
  EXPECT_GT(once, 1e-3) << "the single pass should not already be exact here";
  EXPECT_LT(refined, 1e-6);
  EXPECT_LT(product_error(ChainedFactorization(options(5)), x), once);
}

// A BTF whose every texel holds its own exact product (resolution 3, light 4, view 3).
Btf product_btf(int half_side, bool flat_q) {
  const int res = 3, vs = 3, ls = 4, m = ls * ls, v = vs * vs;
  std::vector<float> rgb(static_cast<std::size_t>(res * res) * v * m * 3);
  for (int t = 0; t < res * res; ++t)
    for (int c = 0; c < 3; ++c) {
      const Product x =
          random_product(ls, vs, half_side, 100u + static_cast<unsigned>(t * 3 + c), flat_q);
      for (int s = 0; s < m * v; ++s)
        rgb[(static_cast<std::size_t>(t) * m * v + s) * 3 + c] = static_cast<float>(x.f[s]);
    }
  return Btf("product", res, vs, ls, std::move(rgb));
}

// 6 x 6 texels, 3 x 3 views and lights.
Btf small_btf(const char* material) {
  BtfParams bp;
  bp.resolution = 6;
  bp.view_side = 3;
  bp.light_side = 3;
  bp.supersampling = 1;
  bp.geometry_grid = 24;
  return generate_btf(make_btf_material(material, 24), bp);
}

std::shared_ptr<const CompressedMaterial> compress(const Btf& btf,
                                                   std::map<std::string, std::string> params) {
  return compress_material("cmf", params, std::make_shared<const Btf>(btf));
}

// f_s = (W q)_s sum_k P_k[j] R_k[e] with `terms` random positive term pairs.
Product random_terms_product(int light_side, int view_side, int half_side, int terms,
                             unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int m = light_side * light_side, v = view_side * view_side, h = half_side * half_side;
  Product x;
  // Each term peaks in its own region of the light and view grids, so no rank-1 product
  // explains their sum.
  for (int k = 0; k < terms; ++k)
    for (int j = 0; j < m; ++j) x.p.push_back(0.05 + u(rng) * (j % terms == k ? 1.0 : 0.1));
  for (int a = 0; a < h; ++a) x.q.push_back(0.2 + 0.8 * u(rng));
  for (int k = 0; k < terms; ++k)
    for (int e = 0; e < v; ++e) x.r.push_back(0.05 + u(rng) * (e % terms == k ? 1.0 : 0.1));
  const auto w = halfway_weights(light_side, view_side, half_side);
  const Eigen::VectorXd q_io = w * Eigen::Map<const Eigen::VectorXd>(x.q.data(), h);
  for (int s = 0; s < m * v; ++s) {
    double a = 0;
    for (int k = 0; k < terms; ++k)
      a += x.p[static_cast<std::size_t>(k * m + s % m)] *
           x.r[static_cast<std::size_t>(k * v + s / m)];
    x.f.push_back(q_io[s] * a);
  }
  return x;
}

// The chain's fit of one ABRDF: its relative L2 error in the original samples.
double fit_error(const ChainedFactorization& c, std::span<const double> f) {
  const int m = c.light_count(), v = c.view_count(), h = c.half_count(), k = c.options().terms;
  std::vector<double> p(static_cast<std::size_t>(k * m)), q(static_cast<std::size_t>(h)),
      r(static_cast<std::size_t>(k * v));
  c.factor(f, p, q, r);
  const auto w =
      halfway_weights(c.options().light_side, c.options().view_side, c.options().half_side);
  const Eigen::VectorXd q_io = w * Eigen::Map<const Eigen::VectorXd>(q.data(), h);
  double err = 0, norm = 0;
  for (int s = 0; s < m * v; ++s) {
    double a = 0;
    for (int l = 0; l < k; ++l)
      a += p[static_cast<std::size_t>(l * m + s % m)] * r[static_cast<std::size_t>(l * v + s / m)];
    err += (q_io[s] * a - f[static_cast<std::size_t>(s)]) *
           (q_io[s] * a - f[static_cast<std::size_t>(s)]);
    norm += f[static_cast<std::size_t>(s)] * f[static_cast<std::size_t>(s)];
  }
  return std::sqrt(err / norm);
}

TEST(Cmf, TwoTermsRecoverASumOfTwoProductsThatOneTermCannot) {
  const Product x = random_terms_product(5, 4, 6, 2, 11);
  const auto chain = [](int terms, int refine) {
    ChainOptions o = options(refine);
    o.terms = terms;
    return ChainedFactorization(o);
  };
  const double one = fit_error(chain(1, 1000), x.f), two = fit_error(chain(2, 1000), x.f);
  EXPECT_GT(one, 5e-2) << "a sum of two distinct products is not rank 1";
  EXPECT_LT(two, 1e-4);
}

// Every ABRDF channel of a BTF as M V doubles (s = view * M + light).
std::vector<std::vector<double>> abrdfs(const Btf& btf) {
  std::vector<std::vector<double>> out;
  const std::size_t n = static_cast<std::size_t>(btf.light_count()) * btf.view_count();
  for (int t = 0; t < btf.texel_count(); ++t)
    for (int c = 0; c < 3; ++c) {
      const float* base = btf.data().data() + btf.offset(t, 0, 0);
      std::vector<double> f(n);
      for (std::size_t s = 0; s < n; ++s) f[s] = base[s * 3 + c];
      out.push_back(std::move(f));
    }
  return out;
}

TEST(Cmf, MoreTermsAndMoreRefinementNeverFitWorse) {
  // Term k joins from P_k = 0 and every later step is an exact non-negative minimiser of its
  // block (Q's too, by coordinate descent where the unconstrained solve goes negative), so the
  // fit of each ABRDF is monotone in the terms and, for one chain, in the refinement sweeps.
  const Btf btf = small_btf("rings");
  ChainOptions o;
  o.light_side = btf.light_side();
  o.view_side = btf.view_side();
  o.half_side = o.diff_side = 6;
  for (const auto& f : abrdfs(btf)) {
    for (int refine : {0, 3}) {
      double previous = 2;
      for (int k = 1; k <= kMaxFactorTerms; ++k) {
        o.terms = k;
        o.refine = refine;
        const double e = fit_error(ChainedFactorization(o), f);
        ASSERT_LE(e, previous * (1 + 1e-9) + 1e-12) << k << " terms, refine " << refine;
        previous = e;
      }
    }
    o.terms = 1;
    double previous = 2;
    for (int refine = 0; refine <= 4; ++refine) {
      o.refine = refine;
      const double e = fit_error(ChainedFactorization(o), f);
      ASSERT_LE(e, previous * (1 + 1e-9) + 1e-12) << "refine " << refine;
      previous = e;
    }
  }
}

TEST(Cmf, MoreTermsNeverLoseThroughTheMaterial) {
  // Float factors, one per texel: the material holds the chain's fit and the scale refit (a
  // non-negative least-squares problem started from the fit's scales) can only lower it.
  for (const char* material : {"rings", "checker"}) {
    const Btf btf = small_btf(material);
    double previous = 2;
    for (const char* terms : {"1", "2", "3"}) {
      const double e = material_error(*compress(btf, {{"half_side", "6"},
                                                      {"quantize", "false"},
                                                      {"clusters", "0"},
                                                      {"refine", "3"},
                                                      {"terms", terms}}),
                                      btf)
                           .relative_l2;
      EXPECT_LE(e, previous * (1 + 1e-5)) << material << ", " << terms << " terms";
      previous = e;
    }
    EXPECT_LT(previous, 0.5 * material_error(*compress(btf, {{"half_side", "6"},
                                                             {"quantize", "false"},
                                                             {"clusters", "0"},
                                                             {"refine", "3"}}),
                                             btf)
                                  .relative_l2)
        << material << ": three terms should clearly beat one";
  }
}

TEST(Cmf, TermsOnTheDeviceMatchTheCppReference) {
  ClContext* ctx = default_context();
  if (ctx == nullptr)
    GTEST_SKIP() << "no OpenCL device on this machine: the device path is not tested here";
  const auto btf = std::make_shared<const Btf>(small_btf("weave"));
  // Parts of 1, 2 and 3 terms in one upload: each row of the part table carries its terms.
  std::vector<std::shared_ptr<const CompressedMaterial>> held;
  for (const char* terms : {"1", "2", "3"})
    held.push_back(compress_material(
        "cmf", {{"half_side", "6"}, {"clusters", "8"}, {"refine", "2"}, {"terms", terms}}, btf));
  const std::vector<const CompressedMaterial*> parts = {held[0].get(), held[1].get(),
                                                        held[2].get()};
  const auto qs = testing::material_queries(3, 5, 60);
  // A few float products and sums per value, in the same order: rounding only.
  std::string where;
  EXPECT_LE(testing::device_vs_cpp_eval_lights(*ctx, parts, qs, btf->light_count(), &where), 1e-6)
      << where;
}

TEST(Cmf, TermsSurviveSaveAndLoadAndAnOlderStateHasOne) {
  const auto btf = std::make_shared<const Btf>(small_btf("checker"));
  const auto m = compress_material(
      "cmf", {{"half_side", "4"}, {"clusters", "5"}, {"refine", "1"}, {"terms", "2"}}, btf);
  const testing::TempDir dir("cmf");
  save_material(*m, dir / "two.prtm");
  const auto loaded = load_material(dir / "two.prtm");
  EXPECT_EQ(dynamic_cast<const FactoredMaterial&>(*loaded).state().terms, 2);
  const auto same = [&](const CompressedMaterial& a, const CompressedMaterial& b) {
    for (int t = 0; t < btf->texel_count(); ++t)
      for (int v = 0; v < btf->view_count(); ++v)
        for (int j = 0; j < btf->light_count(); ++j) {
          const Rgb x = a.reflectance(t, v, j), y = b.reflectance(t, v, j);
          if (std::memcmp(&x, &y, sizeof(Rgb)) != 0) return false;
        }
    return true;
  };
  EXPECT_TRUE(same(*m, *loaded));
  const auto write = [&](const CompressedMaterial& from, const std::filesystem::path& file,
                         const auto& edit) {
    ArchiveWriter w("compressed-material", 1);
    w.add_meta("backend", from.backend());
    from.save(w);
    edit(w.meta().at("factored"));
    w.write(file);
  };
  // A version 2 state (before terms were stored) has one term and reads as it did.
  const auto one = compress_material("cmf", {{"half_side", "4"}, {"clusters", "5"}}, btf);
  write(*one, dir / "v2.prtm", [](nlohmann::json& j) {
    j["format_version"] = 2;
    j.erase("terms");
  });
  const auto old = load_material(dir / "v2.prtm");
  EXPECT_EQ(dynamic_cast<const FactoredMaterial&>(*old).state().terms, 1);
  EXPECT_TRUE(same(*one, *old));
  // Terms out of range, or more than the sections hold, are refused with the file named.
  for (const int bad : {0, kMaxFactorTerms + 1, 3}) {
    const auto file = dir / fmt::format("terms{}.prtm", bad);
    write(*m, file, [&](nlohmann::json& j) { j["terms"] = bad; });
    try {
      (void)load_material(file);
      ADD_FAILURE() << bad << " terms were accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(file.filename().string()), std::string::npos)
          << e.what();
    }
  }
}

TEST(Cmf, EveryTexelOfAProductBtfComesBackThroughTheMaterial) {
  const Btf btf = product_btf(5, false);
  const auto m = compress(
      btf, {{"half_side", "5"}, {"refine", "2000"}, {"clusters", "0"}, {"quantize", "false"}});
  // Float factors and the product's own halfway grid: float rounding only.
  EXPECT_LT(material_error(*m, btf).relative_l2, 1e-5);
  EXPECT_LT(m->declared_error_bound(), 1e-5);
}

TEST(Cmf, AsManyClustersAsTexelsIsLosslessBeforeQuantisation) {
  const Btf btf = small_btf("rings");
  const std::map<std::string, std::string> common = {{"half_side", "6"}, {"quantize", "false"}};
  auto unclustered = common, clustered = common, fewer = common;
  unclustered["clusters"] = "0";
  clustered["clusters"] = std::to_string(btf.texel_count());
  fewer["clusters"] = "4";
  const auto a = compress(btf, unclustered), b = compress(btf, clustered), c = compress(btf, fewer);
  double diff = 0, peak = 0;
  for (int t = 0; t < btf.texel_count(); ++t)
    for (int v = 0; v < btf.view_count(); ++v)
      for (int j = 0; j < btf.light_count(); ++j)
        for (int ch = 0; ch < 3; ++ch) {
          diff = std::max(diff, static_cast<double>(std::abs(a->reflectance(t, v, j)[ch] -
                                                             b->reflectance(t, v, j)[ch])));
          peak = std::max(peak, static_cast<double>(std::abs(a->reflectance(t, v, j)[ch])));
        }
  EXPECT_LE(diff, 1e-6 * peak);
  // ... and the test can tell: 4 clusters for 36 texels do lose something.
  EXPECT_GT(material_error(*c, btf).relative_l2, material_error(*a, btf).relative_l2 + 1e-4);
}

TEST(Cmf, TheScaleRefitNeverIncreasesTheError) {
  // With the same codebooks, the least-squares scale per texel and channel is at least as good
  // as the normalisation's maxima (float storage, so nothing else differs).
  const Btf btf = small_btf("rings");
  for (const char* clusters : {"0", "3"}) {
    const std::map<std::string, std::string> p = {
        {"half_side", "6"}, {"quantize", "false"}, {"clusters", clusters}};
    auto with = p, without = p;
    with["refit_scale"] = "true";
    without["refit_scale"] = "false";
    const double a = material_error(*compress(btf, with), btf).relative_l2;
    const double b = material_error(*compress(btf, without), btf).relative_l2;
    EXPECT_LE(a, b * (1 + 1e-6)) << clusters << " clusters";
  }
}

TEST(Cmf, EightBitStorageStaysWithinTheBoundOfItsSteps) {
  const Btf btf = small_btf("checker");
  // Without the scale refit both keep the normalisation's scales, so only quantisation differs.
  const auto fp =
      compress(btf, {{"half_side", "6"}, {"quantize", "false"}, {"refit_scale", "false"}});
  const auto q8 =
      compress(btf, {{"half_side", "6"}, {"quantize", "true"}, {"refit_scale", "false"}});
  const auto& sf = dynamic_cast<const FactoredMaterial&>(*fp).state();
  const auto& sq = dynamic_cast<const FactoredMaterial&>(*q8).state();
  ASSERT_EQ(sf.index_p, sq.index_p);  // one clustering, then quantisation
  // Each normalised factor value moves by at most half its entry's step (<= 1/510 of the
  // entry's maximum, itself <= 1), the scale by half its channel's step; with all factors in
  // [0, 1] a product P Q R moves by at most the sum of the three moves (plus their products).
  for (int t = 0; t < btf.texel_count(); ++t) {
    const double dp = 0.5 * sq.entry_scale_p[sq.index_p[t]],
                 dq = 0.5 * sq.entry_scale_q[sq.index_q[t]],
                 dr = 0.5 * sq.entry_scale_r[sq.index_r[t]];
    const double prod = (1 + dp) * (1 + dq) * (1 + dr) - 1;
    for (int v = 0; v < btf.view_count(); ++v)
      for (int j = 0; j < btf.light_count(); ++j)
        for (int c = 0; c < 3; ++c) {
          const double s = sf.scale[static_cast<std::size_t>(t) * 3 + c];
          const double ds = 0.5 * sq.scale_global[c] + 1e-6 * s;
          const double bound = (s + ds) * prod * 1.0001 + ds + 1e-7 * s;
          EXPECT_LE(std::abs(fp->reflectance(t, v, j)[c] - q8->reflectance(t, v, j)[c]), bound)
              << "texel " << t << " view " << v << " light " << j << " channel " << c;
        }
  }
}

// The halfway means of g at the GSHD incident directions, interpolated on a light grid of
// `interp_side` whose sample j is read as direction j of the light grid of `light_side`.
std::vector<double> gshd_light_means(const ChainOptions& o, int interp_side,
                                     double (*g)(const Vec3d&), std::vector<double>* analytic) {
  const HemisphereGrid grid(o.light_side), half(o.half_side), diff(o.diff_side);
  std::vector<double> q(static_cast<std::size_t>(half.cell_count()), -1.0);
  if (analytic) analytic->assign(q.size(), -1.0);
  for (int a = 0; a < half.cell_count(); ++a) {
    double interp = 0, exact = 0;
    int n = 0;
    for (int b = 0; b < diff.cell_count(); ++b) {
      const auto [in, out] = gshd_to_in_out(half.direction(a), diff.direction(b));
      if (!(in.z > 0.0 && out.z > 0.0)) continue;
      const BtfViewSamples li = btf_view_samples(interp_side, Vec3(in));
      for (int k = 0; k < 4; ++k) interp += li.weight[k] * g(grid.direction(li.view[k]));
      exact += g(in);
      ++n;
    }
    if (n == 0) continue;  // no valid pair: the chain falls back to the mean of f
    q[static_cast<std::size_t>(a)] = interp / n;
    if (analytic) (*analytic)[static_cast<std::size_t>(a)] = exact / n;
  }
  return q;
}

double light_only(const Vec3d& d) {
  return 4.0 + 3.0 * d.x + d.y;
}

TEST(Cmf, TheResamplingStepReadsTheLightOnTheLightGrid) {
  // f(d, e) = g(d): with `halfway = mean` Q_a is the mean over the valid difference cells b of
  // the resampled f at the GSHD pair (in, out) of (a, b), i.e. of g interpolated on the light
  // grid at `in`, and close to the mean of g(in) itself. Light and view grids differ (6, 5), so
  // that reading the incident direction on the view grid is a mistake the test sees: the
  // negative control computes what that mistake gives (a 5 x 5 grid's samples read as light
  // bins) and must land far from Q.
  ChainOptions o;
  o.light_side = 6;
  o.view_side = 5;
  o.half_side = o.diff_side = 8;
  o.halfway = HalfwayRule::kMean;
  const ChainedFactorization chain(o);
  const int m = chain.light_count(), v = chain.view_count(), h = chain.half_count();
  const HemisphereGrid grid(o.light_side);
  std::vector<double> f(static_cast<std::size_t>(m) * v);
  for (int e = 0; e < v; ++e)
    for (int j = 0; j < m; ++j)
      f[static_cast<std::size_t>(e) * m + j] = light_only(grid.direction(j));
  std::vector<double> p(m), q(h), r(v);
  chain.factor(f, p, q, r);
  std::vector<double> analytic;
  const std::vector<double> want = gshd_light_means(o, o.light_side, light_only, &analytic);
  const std::vector<double> wrong = gshd_light_means(o, o.view_side, light_only, nullptr);
  double exact_err = 0, analytic_err = 0, wrong_err = 0;
  int cells = 0;
  for (int a = 0; a < h; ++a) {
    if (want[static_cast<std::size_t>(a)] < 0) continue;
    ++cells;
    exact_err = std::max(exact_err, std::abs(q[a] - want[static_cast<std::size_t>(a)]));
    analytic_err = std::max(analytic_err, std::abs(q[a] - analytic[static_cast<std::size_t>(a)]));
    wrong_err = std::max(wrong_err, std::abs(wrong[static_cast<std::size_t>(a)] - q[a]));
  }
  ASSERT_GT(cells, h / 2);
  EXPECT_LT(exact_err, 1e-6) << "float weights: rounding of a few 1e-8 of g";
  EXPECT_LT(analytic_err, 0.3) << "interpolation error of g on a 6 x 6 grid (g spans 0.8 .. 7.2)";
  EXPECT_GT(wrong_err, 1.0) << "negative control: the incident direction on the view grid";
}

TEST(Cmf, TheHalfwayFactorCannotSeeALightViewSwap) {
  // With equal grids, swapping light and view in the ABRDF (f'(d, e) = f(e, d), what a swap of
  // the two indices in the resampling reads) maps the GSHD row (a, b) to (a, b'), b' the
  // difference cell mirrored through the halfway axis: the exitant direction is the incident
  // one mirrored about h, and the concentric difference grid is point-symmetric. Both halfway
  // rules (the mean over b, the rank-1 fit over b) are invariant under that permutation of b,
  // so Q is the same: a swapped resampling would be harmless to Q and no test of Q can catch
  // it (the resampling test in tests/core/halfway_parameterization_test.cpp checks the rows).
  for (HalfwayRule rule : {HalfwayRule::kMean, HalfwayRule::kSvd}) {
    ChainOptions o;
    o.light_side = o.view_side = 6;
    o.half_side = o.diff_side = 8;
    o.halfway = rule;
    const ChainedFactorization chain(o);
    const int m = chain.light_count(), h = chain.half_count();
    const HemisphereGrid grid(6);
    std::vector<double> f(static_cast<std::size_t>(m) * m), swapped(f.size());
    for (int e = 0; e < m; ++e)
      for (int j = 0; j < m; ++j) {
        const double x = light_only(grid.direction(j)) * (2.0 - grid.direction(e).y);
        f[static_cast<std::size_t>(e) * m + j] = x;
        swapped[static_cast<std::size_t>(j) * m + e] = x;
      }
    std::vector<double> p(m), q(h), r(m), qs(h);
    chain.factor(f, p, q, r);
    chain.factor(swapped, p, qs, r);
    double diff = 0, peak = 0;
    for (int a = 0; a < h; ++a) {
      diff = std::max(diff, std::abs(q[a] - qs[a]));
      peak = std::max(peak, q[a]);
    }
    EXPECT_LT(diff, 1e-6 * peak) << "rule " << static_cast<int>(rule);
    EXPECT_GT(peak, 1.0);
  }
}

}  // namespace
}  // namespace prt::cmf
