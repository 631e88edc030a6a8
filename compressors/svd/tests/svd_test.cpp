// Material svd: a BTF whose ABRDFs are exactly rank K comes back to float rounding through
// reflectance() and eval_lights() at rank K, and at rank K - 1 its measured error equals the
// bound declared from the discarded singular values; texel_pca is exact with as many components
// as distinct texel ABRDFs (and one fewer: the mean carries one), with its rank-1 error equal to
// the discarded eigenvalues' bound; the OpenCL evaluation equals the C++ reference in both modes;
// storage is the documented formula; save/load is bit-identical and damaged archives are refused
// naming the file. The material conformance suite runs it at its defaults as well.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>

#include "prtlab/base/error.h"
#include "prtlab/btf/btf_generator.h"
#include "prtlab/btf/btf_materials.h"
#include "prtlab/compress/material_error.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/render/device_material_eval.h"
#include "prtlab/storage/archive.h"
#include "support/material_queries.h"
#include "support/temp_dir.h"
#include "svd/svd_material.h"

namespace prt::svd {
namespace {
namespace fs = std::filesystem;

const fs::path g_cache = prt::testing::use_private_cache("svd_material");

using Params = std::map<std::string, std::string>;

// Every ABRDF (texel, channel) is sum_{r < rank} 2^-r x_r(view) y_r(light), with random positive
// x_r, y_r: rank exactly `rank`, with distinct singular values.
std::shared_ptr<const Btf> rank_k_btf(int rank, int res, int view_side, int light_side) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<float> u(0.1f, 1.0f);
  const int v = view_side * view_side, m = light_side * light_side, n = res * res;
  std::vector<float> rgb(static_cast<std::size_t>(n) * v * m * 3, 0.0f);
  for (int t = 0; t < n; ++t)
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < rank; ++r) {
        std::vector<float> x(static_cast<std::size_t>(v)), y(static_cast<std::size_t>(m));
        for (auto& e : x) e = u(rng);
        for (auto& e : y) e = std::ldexp(u(rng), -r);
        for (int a = 0; a < v; ++a)
          for (int j = 0; j < m; ++j)
            rgb[((static_cast<std::size_t>(t) * v + a) * m + j) * 3 + c] += x[a] * y[j];
      }
  return std::make_shared<const Btf>("rank" + std::to_string(rank), res, view_side, light_side,
                                     std::move(rgb));
}

// A U x U tile whose texels take `distinct` random ABRDFs (texel t the (t mod distinct)-th).
std::shared_ptr<const Btf> few_abrdf_btf(int distinct, int res, int view_side, int light_side) {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<float> u(0.0f, 2.0f);
  const std::size_t len =
      static_cast<std::size_t>(view_side * view_side) * light_side * light_side * 3;
  std::vector<std::vector<float>> abrdf(static_cast<std::size_t>(distinct));
  for (auto& a : abrdf) {
    a.resize(len);
    for (auto& e : a) e = u(rng);
  }
  std::vector<float> rgb;
  for (int t = 0; t < res * res; ++t) {
    const auto& a = abrdf[static_cast<std::size_t>(t % distinct)];
    rgb.insert(rgb.end(), a.begin(), a.end());
  }
  return std::make_shared<const Btf>("few", res, view_side, light_side, std::move(rgb));
}

std::shared_ptr<const Btf> generated(const std::string& name, int res, int view_side,
                                     int light_side) {
  BtfParams p;
  p.resolution = res;
  p.view_side = view_side;
  p.light_side = light_side;
  p.supersampling = 1;
  p.geometry_grid = 32;
  return std::make_shared<const Btf>(generate_btf(make_btf_material(name, 32), p));
}

double sample_error(const CompressedMaterial& m, const Btf& btf) {
  double err = 0, peak = 0;
  for (int t = 0; t < btf.texel_count(); ++t)
    for (int v = 0; v < btf.view_count(); ++v)
      for (int j = 0; j < btf.light_count(); ++j) {
        const Rgb a = m.reflectance(t, v, j), b = btf.value(t, v, j);
        for (int c = 0; c < 3; ++c) {
          err = std::max(err, static_cast<double>(std::abs(a[c] - b[c])));
          peak = std::max(peak, static_cast<double>(std::abs(b[c])));
        }
      }
  return err / peak;
}

// eval_lights of the material against Btf::eval_lights (the interpolated full BTF).
double lookup_error(const CompressedMaterial& m, const Btf& btf, TexelFilter filter) {
  const auto qs = testing::material_queries(1, 3);
  const auto dim = static_cast<std::size_t>(btf.light_count());
  std::vector<Rgb> a(qs.size() * dim), b(qs.size() * dim);
  for (std::size_t i = 0; i < qs.size(); ++i) {
    m.eval_lights(qs[i].uv, qs[i].view_local, std::span<Rgb>(a).subspan(i * dim, dim), filter);
    btf.eval_lights(qs[i].uv, qs[i].view_local, std::span<Rgb>(b).subspan(i * dim, dim), filter);
  }
  return testing::max_relative_rgb(a, b);
}

// Float rounding of a sum of at most 16 weighted products of K float factors: a few ulps of the
// peak; one wrong sample or weight is of the order 1e-2.
constexpr double kRounding = 2e-6;

TEST(SvdMaterial, RankKAbrdfsAreReproducedAtRankK) {
  const auto btf = rank_k_btf(3, 3, 3, 4);
  const auto m = compress_material("svd", {{"rank", "3"}}, btf);
  EXPECT_LE(m->declared_error_bound(), 1e-7);
  EXPECT_LE(sample_error(*m, *btf), kRounding);
  for (const auto filter : {TexelFilter::kNearest, TexelFilter::kBilinear})
    EXPECT_LE(lookup_error(*m, *btf, filter), kRounding);
  // The rank-1 truncation of a rank-3 BTF is not: the test can fail.
  const auto low = compress_material("svd", {{"rank", "1"}}, btf);
  EXPECT_GT(sample_error(*low, *btf), 1e-2);
}

TEST(SvdMaterial, RankKMinusOneErrorIsTheDeclaredBound) {
  const auto btf = rank_k_btf(3, 3, 3, 4);
  for (const int rank : {1, 2}) {
    const auto m = compress_material("svd", {{"rank", std::to_string(rank)}}, btf);
    const MaterialError e = material_error(*m, *btf);
    const double bound = m->declared_error_bound();
    EXPECT_GT(bound, 1e-2) << "rank " << rank;
    // Eckart-Young: the truncation's residual is exactly the discarded singular values.
    EXPECT_NEAR(e.relative_l2, bound, 1e-6 * std::max(1.0, bound)) << "rank " << rank;
  }
}

TEST(SvdMaterial, TexelPcaIsExactWithAsManyComponentsAsDistinctAbrdfs) {
  const auto btf = few_abrdf_btf(3, 4, 3, 3);
  for (const int rank : {3, 2}) {
    // Three distinct rows span an affine plane: the mean and two components hold them.
    const auto m =
        compress_material("svd", {{"mode", "texel_pca"}, {"rank", std::to_string(rank)}}, btf);
    EXPECT_LE(m->declared_error_bound(), 1e-7) << "rank " << rank;
    EXPECT_LE(sample_error(*m, *btf), kRounding) << "rank " << rank;
    for (const auto filter : {TexelFilter::kNearest, TexelFilter::kBilinear})
      EXPECT_LE(lookup_error(*m, *btf, filter), kRounding) << "rank " << rank;
  }
  const auto one = compress_material("svd", {{"mode", "texel_pca"}, {"rank", "1"}}, btf);
  const MaterialError e = material_error(*one, *btf);
  EXPECT_GT(one->declared_error_bound(), 1e-2);
  EXPECT_NEAR(e.relative_l2, one->declared_error_bound(), 1e-6);
}

TEST(SvdMaterial, StorageIsTheDocumentedFormula) {
  const auto btf = generated("checker", 4, 3, 4);
  const std::uint64_t u2 = 16, v = 9, m = 16;
  for (const std::uint64_t k : {1u, 3u}) {
    const auto a = compress_material("svd", {{"rank", std::to_string(k)}}, btf);
    EXPECT_EQ(a->storage().total_bytes(), 4 * k * (v + m) * 3 * u2);
    EXPECT_EQ(a->flops_per_pixel(), 2.0 * 4 * k + 2.0 * k * m + 2.0 * m);
    const auto p =
        compress_material("svd", {{"mode", "texel_pca"}, {"rank", std::to_string(k)}}, btf);
    EXPECT_EQ(p->storage().total_bytes(), 4 * ((k + 1) * m * v * 3 + u2 * k));
  }
}

TEST(SvdMaterial, RankBeyondTheMatrixIsRefusedNamingIt) {
  const auto btf = generated("checker", 2, 2, 3);  // V = 4, M = 9, U^2 = 4
  for (const Params& p : {Params{{"rank", "5"}}, Params{{"mode", "texel_pca"}, {"rank", "5"}}}) {
    try {
      compress_material("svd", p, btf);
      ADD_FAILURE() << "rank 5 accepted";
    } catch (const ParameterError& e) {
      EXPECT_NE(std::string(e.what()).find("rank 5"), std::string::npos) << e.what();
    }
  }
  EXPECT_NO_THROW(compress_material("svd", {{"rank", "4"}}, btf));
  EXPECT_NO_THROW(compress_material("svd", {{"mode", "texel_pca"}, {"rank", "4"}}, btf));
  // 65 x 65 texels: beyond the Gram matrix texel_pca builds.
  const auto wide =
      std::make_shared<const Btf>("wide", 65, 1, 1, std::vector<float>(65 * 65 * 3, 0.5f));
  try {
    compress_material("svd", {{"mode", "texel_pca"}}, wide);
    ADD_FAILURE() << "4225 texels accepted";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("4225"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(compress_material("svd", {}, wide));
}

TEST(SvdMaterial, OpenClEqualsTheCppReferenceInBothModes) {
  ClContext* ctx = default_context();
  if (ctx == nullptr) GTEST_SKIP() << "no OpenCL device on this machine";
  // M = 25: 75 floats, a 3-float tail past the 12-float chunks; two parts with other BTFs,
  // resolutions and ranks.
  const auto first = generated("weave", 4, 4, 5), second = generated("rings", 3, 3, 5);
  for (const auto& [mode, ranks] : std::vector<std::pair<std::string, std::pair<int, int>>>{
           {"abrdf", {3, 2}}, {"texel_pca", {5, 9}}}) {
    const auto a =
        compress_material("svd", {{"mode", mode}, {"rank", std::to_string(ranks.first)}}, first);
    const auto b =
        compress_material("svd", {{"mode", mode}, {"rank", std::to_string(ranks.second)}}, second);
    const std::vector<const CompressedMaterial*> parts = {a.get(), b.get()};
    const auto qs = testing::material_queries(2, 5);
    for (const auto filter : {TexelFilter::kNearest, TexelFilter::kBilinear}) {
      SCOPED_TRACE(mode + (filter == TexelFilter::kNearest ? " nearest" : " bilinear"));
      const auto gpu = evaluate_materials_on_device(*ctx, parts, qs, filter);
      const auto dim = static_cast<std::size_t>(a->light_basis().dim);
      std::vector<Rgb> cpp(qs.size() * dim);
      for (std::size_t i = 0; i < qs.size(); ++i)
        parts[static_cast<std::size_t>(qs[i].part)]->eval_lights(
            qs[i].uv, qs[i].view_local, std::span<Rgb>(cpp).subspan(i * dim, dim), filter);
      ASSERT_EQ(gpu.size(), cpp.size());
      EXPECT_LE(testing::max_relative_rgb(gpu, cpp), 1e-5);
    }
  }
  const auto abrdf = compress_material("svd", {}, first);
  const auto pca = compress_material("svd", {{"mode", "texel_pca"}}, first);
  const std::vector<const CompressedMaterial*> mixed = {abrdf.get(), pca.get()};
  EXPECT_THROW(upload_materials(*ctx, mixed), ParameterError);
}

std::vector<Rgb> all_samples(const CompressedMaterial& m) {
  const MaterialSampling s = m.sampling();
  std::vector<Rgb> out;
  for (int t = 0; t < s.texel_count(); ++t)
    for (int v = 0; v < s.view_count(); ++v)
      for (int j = 0; j < s.light_count(); ++j) out.push_back(m.reflectance(t, v, j));
  return out;
}

TEST(SvdMaterial, SaveLoadIsBitIdenticalAndDamageIsRefused) {
  const auto btf = generated("bumps", 3, 3, 3);
  prt::testing::TempDir dir;
  for (const std::string mode : {"abrdf", "texel_pca"}) {
    const auto m = compress_material("svd", {{"mode", mode}, {"rank", "2"}}, btf);
    const fs::path file = dir.path() / (mode + ".prt");
    save_material(*m, file);
    const auto back = load_material(file);
    const auto* a = dynamic_cast<const SvdMaterial*>(m.get());
    const auto* b = dynamic_cast<const SvdMaterial*>(back.get());
    ASSERT_NE(b, nullptr);
    EXPECT_EQ(a->mode(), b->mode());
    EXPECT_EQ(a->rank(), b->rank());
    EXPECT_EQ(a->state().view_factors, b->state().view_factors);
    EXPECT_EQ(a->state().light_factors, b->state().light_factors);
    EXPECT_EQ(a->state().mean, b->state().mean);
    EXPECT_EQ(a->state().components, b->state().components);
    EXPECT_EQ(a->state().coefficients, b->state().coefficients);
    EXPECT_EQ(a->declared_error_bound(), b->declared_error_bound());
    const auto sa = all_samples(*a), sb = all_samples(*b);
    ASSERT_EQ(sa.size(), sb.size());
    EXPECT_EQ(std::memcmp(sa.data(), sb.data(), sa.size() * sizeof(Rgb)), 0);
  }
  const fs::path good = dir.path() / "abrdf.prt";
  const ArchiveReader r = ArchiveReader::open(good);
  auto rewrite = [&](const std::string& name, auto edit_meta, auto edit_light) {
    ArchiveWriter w(r.kind(), r.kind_version());
    for (const auto& [k, v] : r.meta().items()) w.add_meta(k, v);
    edit_meta(w.meta());
    const auto light = r.view<float>("light_factors");
    std::vector<float> l(light.begin(), light.end());
    edit_light(l);
    w.add_section("view_factors", r.view<float>("view_factors"));
    w.add_section("light_factors", l);
    const fs::path f = dir.path() / name;
    w.write(f);
    return f;
  };
  const auto keep = [](auto&) {};
  const std::vector<fs::path> damaged = {
      rewrite(
          "version.prt", [](nlohmann::json& m) { m["svd"]["format_version"] = 99; }, keep),
      rewrite(
          "mode.prt", [](nlohmann::json& m) { m["svd"]["mode"] = "tucker"; }, keep),
      rewrite(
          "rank.prt", [](nlohmann::json& m) { m["svd"]["rank"] = 0; }, keep),
      rewrite(
          "rank_big.prt", [](nlohmann::json& m) { m["svd"]["rank"] = 10; }, keep),
      rewrite(
          "residual.prt", [](nlohmann::json& m) { m["svd"]["discarded"] = -1.0; }, keep),
      rewrite(
          "missing.prt", [](nlohmann::json& m) { m["svd"].erase("total"); }, keep),
      rewrite("nan.prt", keep, [](std::vector<float>& l) { l[1] = std::nanf(""); }),
      rewrite("short.prt", keep, [](std::vector<float>& l) { l.pop_back(); })};
  for (const auto& f : damaged) {
    try {
      load_material(f);
      ADD_FAILURE() << f << " was loaded";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), f);
    }
  }
  EXPECT_NE(load_material(good), nullptr);
}

}  // namespace
}  // namespace prt::svd
