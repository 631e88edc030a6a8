// Backend `cpca_sh`, beyond the conformance suite: relight against reconstruct-then-multiply in
// double, exactness when the affine subspace spans the signals (both projections, and the
// paper's non-square output), the least-squares projection reproducing band-limited radiance on
// a free plane where the zero-hemisphere one has its analytic error, least squares against zero
// at the same CPCA parameters on a shadowed scene (against T L), the error falling with the
// vectors, the accounting, save/load of every variant and a corrupt file, and OpenCL against
// C++.
#include "cpca_sh/cpca_sh.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstring>
#include <filesystem>

#include "prtlab/base/error.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/transfer_error.h"
#include "prtlab/numeric/float16.h"
#include "prtlab/opencl/cl_buffer.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/sphere/hemisphere_projection.h"
#include "prtlab/storage/archive.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/transfer/radiance_to_bins.h"
#include "support/conformance_helpers.h"
#include "support/synthetic_cases.h"
#include "support/temp_dir.h"

namespace prt::cpca_sh {
namespace {
namespace fs = std::filesystem;

const fs::path g_cache_root = prt::testing::use_private_cache("cpca_sh");

using Params = std::map<std::string, std::string>;
using conformance::CaseData;

const CaseData& scene() {
  return conformance::case_data("sphere_over_plane");
}

std::unique_ptr<CompressedTransfer> compress(const CaseData& c, const Params& p) {
  const CompressorEntry& entry = CompressorRegistry::instance().get(std::string(kName));
  return CompressorRegistry::instance()
      .create(std::string(kName), p)
      ->compress(c.input(entry), Progress::null());
}

const CpcaShArrays& arrays(const CompressedTransfer& ct) {
  return dynamic_cast<const CpcaShTransfer&>(ct).arrays();
}

double stored_weight(const CpcaShArrays& a, std::size_t p, std::size_t i) {
  switch (a.format) {
    case WeightFormat::kFloat32:
      return a.weights32[i];
    case WeightFormat::kFloat16:
      return half_to_float(a.weights16[i]);
    case WeightFormat::kS8:
      return static_cast<double>(a.codes[i]) * a.vertex_scales[p];
  }
  return 0;
}

// X~_p (rows x n) from the stored arrays, in double.
Eigen::MatrixXd reconstruct(const CpcaShArrays& a, std::size_t p) {
  const Eigen::Index rows = a.rows(), n = a.n();
  const std::size_t dim = a.signal_dim();
  const auto rep = [&](std::size_t r) {
    Eigen::MatrixXd m(rows, n);
    for (Eigen::Index i = 0; i < rows; ++i)
      for (Eigen::Index k = 0; k < n; ++k)
        m(i, k) = a.reps[r * dim + static_cast<std::size_t>(i * n + k)];
    return m;
  };
  const std::uint32_t c = a.ids[p];
  Eigen::MatrixXd x = rep(a.first[c]);
  for (int i = 0; i < a.vectors_of(c); ++i)
    x += stored_weight(a, p, a.weight_offsets[p] + static_cast<std::size_t>(i)) *
         rep(a.first[c] + 1 + static_cast<std::size_t>(i));
  return x;
}

Eigen::MatrixXd light_matrix(const LightCoeffs& l) {
  Eigen::MatrixXd m(static_cast<Eigen::Index>(l.values.size()), 3);
  for (std::size_t k = 0; k < l.values.size(); ++k)
    for (int ch = 0; ch < 3; ++ch) m(static_cast<Eigen::Index>(k), ch) = l.values[k][ch];
  return m;
}

// ||a - b|| / ||b|| over all values and channels, in double.
double relative_difference(const LocalRadiance& a, const LocalRadiance& b) {
  double d = 0, n = 0;
  for (std::size_t i = 0; i < b.values.size(); ++i)
    for (int ch = 0; ch < 3; ++ch) {
      const double e = static_cast<double>(a.values[i][ch]) - b.values[i][ch];
      d += e * e;
      n += static_cast<double>(b.values[i][ch]) * b.values[i][ch];
    }
  return n > 0 ? std::sqrt(d / n) : std::sqrt(d);
}

LocalRadiance exact_product(const CaseData& c, const Cubemap& light) {
  const auto d = relight_exact_double(c.transfer, light.light_vector());
  LocalRadiance out(RadianceBasis::kPixel, c.transfer.local_count(), c.transfer.vertex_count());
  for (std::size_t i = 0; i < d.size(); ++i) out.values[i] = Rgb(d[i]);
  return out;
}

LocalRadiance relight(const CompressedTransfer& ct, const Cubemap& light) {
  LocalRadiance out;
  ct.relight(ct.project_light(light), out);
  return out;
}

// L(d) = 1 + 0.6 d.a + 0.4 (d.e)^2 >= 0.2: a light of SH order 3.
double smooth_radiance(const Vec3d& d) {
  const Vec3d a = glm::normalize(Vec3d(0.3, 0.8, -0.2)), e = glm::normalize(Vec3d(1, 0.2, 0.5));
  return 1.0 + 0.6 * glm::dot(d, a) + 0.4 * glm::dot(d, e) * glm::dot(d, e);
}

Cubemap smooth_light(int resolution) {
  Cubemap light(resolution);
  for (int k = 0; k < light.layout.pixel_count(); ++k)
    light.radiance[k] = Rgb(static_cast<float>(smooth_radiance(light.layout.direction(k))));
  return light;
}

const std::vector<Params> kVariants = {
    {{"clusters", "6"}, {"vectors", "3"}, {"method", "static"}},
    {{"clusters", "6"}, {"vectors", "3"}, {"weights", "float16"}, {"projection", "zero"}},
    {{"clusters", "5"}, {"vectors", "2"}, {"method", "adaptive"}, {"weights", "s8"}},
    {{"clusters", "4"}, {"vectors", "2"}, {"order", "4"}, {"output_order", "3"}},
    {{"clusters", "4"}, {"vectors", "0"}},  // pure VQ
};

std::string describe(const Params& p) {
  std::string s;
  for (const auto& [k, v] : p) s += k + "=" + v + " ";
  return s;
}

// The relight is X~_p l per vertex with X~_p the stored model: within float rounding of the
// sums (1e-5 of the sum of magnitudes is far above it and far below any modelling error).
TEST(CpcaSh, RelightIsReconstructThenMultiply) {
  for (const Params& p : kVariants) {
    SCOPED_TRACE(describe(p));
    const auto ct = compress(scene(), p);
    const CpcaShArrays& a = arrays(*ct);
    const LightCoeffs l = ct->project_light(scene().lights[0]);
    ASSERT_EQ(l.basis, fmt::format("sh{}", a.order));
    const Eigen::MatrixXd lm = light_matrix(l);
    LocalRadiance out;
    ct->relight(l, out);
    ASSERT_EQ(out.basis, RadianceBasis::kSphericalHarmonics);
    ASSERT_EQ(out.dim, a.rows());
    ASSERT_EQ(out.vertices, a.vertices);
    for (std::size_t v = 0; v < a.vertices; ++v) {
      const Eigen::MatrixXd x = reconstruct(a, v);
      const Eigen::MatrixXd want = x * lm;
      const Eigen::MatrixXd mag = x.cwiseAbs() * lm.cwiseAbs();
      for (Eigen::Index i = 0; i < want.rows(); ++i)
        for (int ch = 0; ch < 3; ++ch)
          ASSERT_NEAR(out.values[v * a.rows() + i][ch], want(i, ch), 1e-5 * (mag(i, ch) + 1e-4))
              << "vertex " << v << ", row " << i;
    }
  }
}

// One cluster with vertices - 1 vectors spans every signal, so the relight is the uncompressed
// product: M_p l (zero), A^-1 M_p l (least squares), and for output_order 4 the least-squares
// projection of order 4 of the first 16 rows of M_p (not a cut of the order-5 one).
TEST(CpcaSh, SpanningSubspaceIsTheUncompressedProduct) {
  const CaseData& c = scene();
  const ShTransfer& sh = c.sh(kInputOrder);
  const std::string spanning = std::to_string(c.transfer.vertex_count() - 1);
  for (const auto& [projection, output] : std::vector<std::pair<std::string, int>>{
           {"zero", 5}, {"least_squares", 5}, {"least_squares", 4}}) {
    SCOPED_TRACE(projection + ", output order " + std::to_string(output));
    const auto ct = compress(c, {{"clusters", "1"},
                                 {"vectors", spanning},
                                 {"method", "static"},
                                 {"projection", projection},
                                 {"output_order", std::to_string(output)}});
    EXPECT_LT(arrays(*ct).signal_error, 1e-6);
    const LightCoeffs l = ct->project_light(c.lights[0]);
    const Eigen::MatrixXd lm = light_matrix(l);
    LocalRadiance out;
    ct->relight(l, out);
    const int rows = output * output;
    const HemisphereProjector projector(output);
    double diff = 0, norm = 0;
    for (std::size_t v = 0; v < sh.vertex_count(); ++v) {
      const Eigen::MatrixXd b = (sh.map(v) * lm).topRows(rows);
      Eigen::MatrixXd want = b;
      if (projection == "least_squares")
        for (int ch = 0; ch < 3; ++ch) want.col(ch) = projector.solve(b.col(ch));
      for (int i = 0; i < rows; ++i)
        for (int ch = 0; ch < 3; ++ch) {
          const double e = out.values[v * rows + i][ch] - want(i, ch);
          diff += e * e;
          norm += want(i, ch) * want(i, ch);
        }
    }
    EXPECT_LT(std::sqrt(diff / norm), 1e-5);
  }
}

// A free plane (no occluder) under a light of SH order 3: the incident radiance on each
// vertex's hemisphere is L(F w), band-limited, so the least-squares projection reproduces its
// local SH coefficients c (up to the quadrature of M_p), while the zero-hemisphere projection
// b = A c has the squared error over H of (b - c)^T A (b - c) = c^T Q1 c, Q1 =
// hemisphere_projection_error_matrix (appendix 9.2). Errors are RMS over H, relative to the
// radiance's own: sqrt(e^T A e / c^T A c). At the bins, against the exact pixel-basis product,
// least squares is then as close as T's own discretisation allows and zero is not.
TEST(CpcaSh, LeastSquaresReproducesBandLimitedRadianceOnAFreePlane) {
  const Mesh bare = make_plane(2.0, 2.0, 2);
  Mesh storage;
  const Mesh& plane = mesh_with_frames(bare, storage);
  TransferParams tp;
  tp.cubemap_resolution = 16;
  tp.local_grid = 4;
  tp.supersampling = 4;
  tp.sh_order = kInputOrder;
  tp.show_progress = false;
  const TransferResult tr = compute_transfer(plane, tp);
  auto c = conformance::make_case("free_plane", "free plane", tr.transfer, 16, 4, 3);
  const ShTransfer sh = *tr.sh;
  c->make_sh = [sh](const CaseData&, int) { return sh; };

  const Cubemap light = smooth_light(16);
  const auto radiance = smooth_radiance;

  const Eigen::MatrixXd gram = hemisphere_gram(kInputOrder);
  const Eigen::MatrixXd q1 = hemisphere_projection_error_matrix(
      HemisphereProjectionKind::kZeroHemisphere, kInputOrder, kInputOrder);
  const auto a_norm = [&](const Eigen::VectorXd& x) { return std::sqrt(x.dot(gram * x)); };
  const int n = sh_count(kInputOrder);
  std::map<std::string, double> bins_error;
  for (const std::string projection : {"zero", "least_squares"}) {
    SCOPED_TRACE(projection);
    const auto ct = compress(*c, {{"clusters", "1"}, {"vectors", "0"}, {"projection", projection}});
    const LocalRadiance out = relight(*ct, light);
    for (std::size_t v = 0; v < plane.vertex_count(); ++v) {
      // The local coefficients of L(F w), by a fine cubemap quadrature of the rotated light.
      const LocalFrame f = plane.frame(v);
      Cubemap local(64);
      for (int k = 0; k < local.layout.pixel_count(); ++k)
        local.radiance[k] =
            Rgb(static_cast<float>(radiance(f.to_world(local.layout.direction(k)))));
      const ShCoeffs exact = sh_project(local, kInputOrder);
      Eigen::VectorXd want(n), got(n);
      for (int i = 0; i < n; ++i) {
        want[i] = exact.coeffs[i].x;
        got[i] = out.values[v * n + i].x;
      }
      const double error = a_norm(got - want) / a_norm(want);
      if (projection == "least_squares") {
        EXPECT_LT(error, 5e-3) << "vertex " << v;
      } else {
        const double analytic = std::sqrt(want.dot(q1 * want)) / a_norm(want);
        EXPECT_NEAR(error, analytic, 0.05 * analytic + 5e-3) << "vertex " << v;
        EXPECT_GT(analytic, 0.02);
      }
    }
    bins_error[projection] =
        relative_difference(to_pixel_basis(out, c->grid), exact_product(*c, light));
  }
  RecordProperty("bins_error_zero", fmt::format("{:.4g}", bins_error["zero"]));
  RecordProperty("bins_error_least_squares", fmt::format("{:.4g}", bins_error["least_squares"]));
  EXPECT_LT(bins_error["least_squares"], 0.5 * bins_error["zero"]);
}

// On the shadowed scene, at the same CPCA parameters (and metric), the least-squares signals
// relight closer to the exact pixel-basis product T L than the zero-hemisphere ones, both
// uncompressed and compressed. The transferred radiance is not band-limited here, so this is
// the paper's measured claim (figure 7) rather than an identity; the lights are the smooth one
// and the random one (the HDR light's error is its own SH truncation, the same for both).
TEST(CpcaSh, LeastSquaresBeatsZeroAgainstTheExactProduct) {
  const CaseData& c = scene();
  const std::string spanning = std::to_string(c.transfer.vertex_count() - 1);
  const std::vector<Params> settings = {
      {{"clusters", "1"}, {"vectors", spanning}, {"method", "static"}},
      {{"clusters", "8"}, {"vectors", "4"}},
  };
  for (const Cubemap& light : {smooth_light(8), c.lights[0]}) {
    const LocalRadiance exact = exact_product(c, light);
    for (const Params& p : settings) {
      SCOPED_TRACE(describe(p));
      std::map<std::string, double> error;
      for (const std::string projection : {"zero", "least_squares"}) {
        Params q = p;
        q["projection"] = projection;
        error[projection] =
            relative_difference(to_pixel_basis(relight(*compress(c, q), light), c.grid), exact);
      }
      EXPECT_LT(error["least_squares"], 0.97 * error["zero"]);
    }
  }
}

// More vectors never cost signal error (each added vector's passes start from the previous
// subspace), and with them the relight approaches the uncompressed one at the bins.
TEST(CpcaSh, ErrorFallsWithTheVectors) {
  const CaseData& c = scene();
  const std::string spanning = std::to_string(c.transfer.vertex_count() - 1);
  const auto full = compress(c, {{"clusters", "1"}, {"vectors", spanning}, {"method", "static"}});
  const Cubemap light = smooth_light(8);
  const LocalRadiance reference = to_pixel_basis(relight(*full, light), c.grid);
  double previous_signal = 1e300, first_relight = 0, last_relight = 0;
  for (int k = 0; k <= 6; k += 2) {
    const auto ct = compress(c, {{"clusters", "6"}, {"vectors", std::to_string(k)}});
    const double s = arrays(*ct).signal_error;
    const double r = relative_difference(to_pixel_basis(relight(*ct, light), c.grid), reference);
    EXPECT_LE(s, previous_signal * (1 + 1e-6)) << "vectors " << k;
    if (k == 0) first_relight = r;
    last_relight = r;
    previous_signal = s;
  }
  EXPECT_GT(first_relight, 0.0);
  EXPECT_LT(last_relight, 0.75 * first_relight);
}

TEST(CpcaSh, StorageAndFlopsFollowTheLayout) {
  const auto ct = compress(scene(), {{"clusters", "6"}, {"vectors", "3"}, {"output_order", "4"}});
  const CpcaShArrays& a = arrays(*ct);
  const std::uint64_t vertices = scene().transfer.vertex_count();
  ASSERT_EQ(a.clusters(), 6u);
  ASSERT_EQ(a.rep_count(), 6u * 4);
  EXPECT_EQ(ct->storage().total_bytes(), vertices * 1 + vertices * 3 * 4 + 6 * 4 * 16 * 25 * 4);
  // The paper's count: per cluster (n' + 1) rows n products, per vertex n' rows blend.
  EXPECT_EQ(ct->flops_per_relight(),
            6.0 * 4 * 16 * 25 * 2 + static_cast<double>(vertices) * 2 * 3 * 16);
  ASSERT_TRUE(ct->expected_frobenius_error().has_value());
  EXPECT_EQ(*ct->expected_frobenius_error(), a.frobenius_error);
  EXPECT_EQ(ct->declared_error_bound(), kNoErrorBound);
}

TEST(CpcaSh, ParametersAndInputsAreChecked) {
  EXPECT_THROW(compress(scene(), {{"order", "3"}, {"output_order", "4"}}), ParameterError);
  const CaseData& c = scene();
  const std::string spanning = std::to_string(c.transfer.vertex_count() - 1);
  auto compressor = CompressorRegistry::instance().create(
      std::string(kName), {{"clusters", "1"}, {"vectors", spanning}, {"method", "static"}});
  EXPECT_THROW(compressor->compress(c.input(), Progress::null()), ParameterError);
  TransferInput low = c.input();
  low.sh = &c.sh(3);
  EXPECT_THROW(compressor->compress(low, Progress::null()), ParameterError);
  // A higher-order input is cut to the parameter's order.
  const CompressorEntry& entry = CompressorRegistry::instance().get(std::string(kName));
  TransferInput high = c.input(entry);
  high.sh = &c.sh(6);
  const auto from_high = compressor->compress(high, Progress::null());
  const auto from_five = compressor->compress(c.input(entry), Progress::null());
  const LocalRadiance a = relight(*from_high, c.lights[0]), b = relight(*from_five, c.lights[0]);
  EXPECT_LT(relative_difference(a, b), 1e-5);
  LocalRadiance out;
  EXPECT_THROW(from_five->relight({"sh4", std::vector<Rgb>(16)}, out), ParameterError);
  EXPECT_THROW(from_five->relight({"pixel", c.lights[0].light_vector()}, out), ParameterError);
}

TEST(CpcaSh, SaveLoadRoundTripsEveryVariantAndRefusesACorruptFile) {
  for (const Params& p : kVariants) {
    SCOPED_TRACE(describe(p));
    const auto ct = compress(scene(), p);
    prt::testing::ScratchFile file(g_cache_root, "cpca_sh_roundtrip");
    save_compressed(*ct, file.path);
    const auto loaded = load_compressed(file.path);
    const CpcaShArrays &a = arrays(*ct), &b = arrays(*loaded);
    EXPECT_EQ(a.reps, b.reps);
    EXPECT_EQ(a.ids, b.ids);
    EXPECT_EQ(a.first, b.first);
    EXPECT_EQ(a.weight_values, b.weight_values);
    EXPECT_EQ(a.vertex_scales, b.vertex_scales);
    EXPECT_EQ(a.order, b.order);
    EXPECT_EQ(a.output_order, b.output_order);
    EXPECT_EQ(a.projection, b.projection);
    EXPECT_EQ(a.signal_error, b.signal_error);
    const LocalRadiance x = relight(*ct, scene().lights[1]),
                        y = relight(*loaded, scene().lights[1]);
    ASSERT_EQ(x.values.size(), y.values.size());
    EXPECT_EQ(std::memcmp(x.values.data(), y.values.data(), x.values.size() * sizeof(Rgb)), 0);
  }
  CpcaShArrays bad = arrays(*compress(scene(), {{"clusters", "3"}, {"vectors", "1"}}));
  bad.ids[1] = 7;
  prt::testing::ScratchFile file(g_cache_root, "cpca_sh_corrupt");
  save_compressed(CpcaShTransfer(bad), file.path);
  try {
    load_compressed(file.path);
    FAIL() << "loaded an out-of-range cluster id";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(file.path.filename().string()), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("'cluster_ids'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("out of range"), std::string::npos) << e.what();
  }
}

// The device path against the C++ reference, for u8 ids, every weight format, the adaptive
// layout, the non-square output, and a vertex subset.
TEST(CpcaSh, OpenClMatchesTheCppReference) {
  ClContext* ctx = default_context();
  if (ctx == nullptr) GTEST_SKIP() << "no OpenCL device on this machine";
  for (const Params& p : kVariants) {
    SCOPED_TRACE(describe(p));
    const auto ct = compress(scene(), p);
    auto device = upload_compressed(*ct, *ctx);
    ASSERT_NE(device, nullptr);
    for (const Cubemap& light : scene().lights) {
      const LightCoeffs l = ct->project_light(light);
      LocalRadiance cpp, gpu;
      ct->relight(l, cpp);
      device->relight(l, gpu);
      ASSERT_EQ(gpu.values.size(), cpp.values.size());
      EXPECT_LT(relative_difference(gpu, cpp), 1e-5);
      EXPECT_LT(max_relative_error(gpu, cpp), 1e-5);
    }
    const std::vector<std::uint32_t> subset{0, 3, 4, 10};
    const LightCoeffs l = ct->project_light(scene().lights[1]);
    LocalRadiance full, out;
    device->relight(l, full);
    device->relight(ct->project_light(scene().lights[0]), out);
    device->set_vertex_subset(subset);
    device->relight_subset_on_device(l);
    download(*ctx, device->output_buffer(), std::span<Rgb>(out.values), "cpca_sh subset");
    const auto rows = static_cast<std::size_t>(arrays(*ct).rows());
    for (const std::uint32_t v : subset)
      for (std::size_t i = 0; i < rows; ++i)
        EXPECT_EQ(std::memcmp(&out.values[v * rows + i], &full.values[v * rows + i], sizeof(Rgb)),
                  0);
  }
}

}  // namespace
}  // namespace prt::cpca_sh
