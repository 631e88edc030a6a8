// Backend `cpca` on the BRDF-weighted signal (signal=brdf, core compress/brdf_signal.h): the
// relight against Phi Psi T_x L computed densely from T by the core fold (exact when every row
// is its own cluster), the stored error against a dense recomputation over the view cells, the
// OpenCL view kernel against the C++ relight, save/load, and the refusals.
#include <gtest/gtest.h>

#include <cmath>

#include "cpca/cpca.h"
#include "prtlab/base/error.h"
#include "prtlab/compress/brdf_signal.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/transfer/brdf_weighted_transfer.h"
#include "prtlab/transfer/random_transfer.h"
#include "prtlab/transfer/transfer_matrix.h"
#include "support/temp_dir.h"
#include "support/test_light.h"

namespace prt::cpca {
namespace {

const std::filesystem::path g_cache_root = prt::testing::use_private_cache("cpca_brdf");

using Params = std::map<std::string, std::string>;

// 30 vertices, M = 9 (S = 3), N = 54: room for K = 4 terms below M.
TransferMatrix test_transfer() {
  return random_transfer(11, RandomTransferSpec{30, 3, 3, 4, 0.5, {5}});
}

std::unique_ptr<CompressedTransfer> compress(const TransferMatrix& t, Params p) {
  p["signal"] = "brdf";
  p.try_emplace("brdf_terms", "4");
  const CubemapLayout cubemap(3);
  const HemisphereGrid grid(3);
  return CompressorRegistry::instance()
      .create(std::string(kName), p)
      ->compress({t, nullptr, cubemap, grid}, Progress::null());
}

const CpcaArrays& arrays(const CompressedTransfer& ct) {
  return dynamic_cast<const CpcaTransfer&>(ct).arrays();
}

// Phi Psi T_x for every vertex (rows vertex * M + view cell), densely from the core fold.
Eigen::MatrixXd outgoing_reference(const TransferMatrix& t, const BrdfFold& fold) {
  const int m = t.local_count();
  Eigen::MatrixXd out(static_cast<Eigen::Index>(t.rows()), static_cast<Eigen::Index>(t.cols()));
  for (std::size_t x = 0; x < t.vertex_count(); ++x)
    out.middleRows(static_cast<Eigen::Index>(x) * m, m) = fold.view * folded_vertex(t, fold, x);
  return out;
}

// The stored model's rows (vertex * K + term), densely in double, then through the stored Phi.
Eigen::MatrixXd outgoing_model(const CpcaArrays& a) {
  const auto n = static_cast<std::size_t>(a.pixel_count);
  const auto k = static_cast<std::size_t>(a.view_terms);
  const auto m = static_cast<std::size_t>(a.local_count);
  Eigen::MatrixXd rows(static_cast<Eigen::Index>(a.rows()), static_cast<Eigen::Index>(n));
  for (std::size_t r = 0; r < a.rows(); ++r) {
    const std::uint32_t c = a.ids[r];
    const double scale = a.format == WeightFormat::kS8 ? a.row_scales[r] : 1.0;
    for (std::size_t j = 0; j < n; ++j) {
      double v = a.reps[a.first[c] * n + j];
      for (int i = 0; i < a.vectors_of(c); ++i)
        v += scale * a.weight_values[a.weight_offsets[r] + static_cast<std::size_t>(i)] *
             a.reps[(a.first[c] + 1 + static_cast<std::size_t>(i)) * n + j];
      rows(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(j)) = v;
    }
  }
  Eigen::MatrixXd phi(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(k));
  for (std::size_t o = 0; o < m; ++o)
    for (std::size_t i = 0; i < k; ++i)
      phi(static_cast<Eigen::Index>(o), static_cast<Eigen::Index>(i)) = a.view[o * k + i];
  Eigen::MatrixXd out(static_cast<Eigen::Index>(a.vertices * m), static_cast<Eigen::Index>(n));
  for (std::size_t x = 0; x < a.vertices; ++x)
    out.middleRows(static_cast<Eigen::Index>(x * m), static_cast<Eigen::Index>(m)) =
        phi * rows.middleRows(static_cast<Eigen::Index>(x * k), static_cast<Eigen::Index>(k));
  return out;
}

// ||relight - D L|| / ||D L|| over every row and channel, D dense with pixel-basis rows.
double relative_error(const LocalRadiance& got, const Eigen::MatrixXd& d,
                      const std::vector<Rgb>& light) {
  double se = 0, n2 = 0;
  for (Eigen::Index r = 0; r < d.rows(); ++r) {
    for (int ch = 0; ch < 3; ++ch) {
      double want = 0;
      for (Eigen::Index j = 0; j < d.cols(); ++j) want += d(r, j) * light[j][ch];
      se += std::pow(got.values[r][ch] - want, 2);
      n2 += want * want;
    }
  }
  return std::sqrt(se / n2);
}

TEST(CpcaBrdfSignal, OneRowPerClusterRelightsTheFoldedTransferExactly) {
  const TransferMatrix t = test_transfer();
  const BrdfFold fold = fold_brdf(HemisphereGrid(3), CookTorrance{}, 4);
  // 120 folded rows, each its own cluster: the mean is the row, in f32.
  const auto ct = compress(t, {{"clusters", "120"}, {"vectors", "0"}, {"method", "static"}});
  const CpcaArrays& a = arrays(*ct);
  ASSERT_EQ(a.view_terms, 4);
  ASSERT_EQ(a.rows(), 120u);
  EXPECT_LT(a.frobenius_error, 1e-6);
  const std::vector<Rgb> light = prt::testing::pseudo_random_light(t.cols(), 3, 2.0f);
  LocalRadiance out;
  ct->relight({"pixel", light}, out);
  ASSERT_EQ(out.values.size(), t.rows());  // M outgoing values per vertex
  EXPECT_LT(relative_error(out, outgoing_reference(t, fold), light), 1e-5);
}

TEST(CpcaBrdfSignal, StoredErrorIsTheErrorOverTheViewCells) {
  const TransferMatrix t = test_transfer();
  const Eigen::MatrixXd ref =
      outgoing_reference(t, fold_brdf(HemisphereGrid(3), CookTorrance{}, 4));
  const std::vector<Rgb> light = prt::testing::pseudo_random_light(t.cols(), 8, 2.0f);
  for (const char* weights : {"float32", "s8"}) {
    SCOPED_TRACE(weights);
    const auto ct = compress(t, {{"clusters", "5"}, {"vectors", "2"}, {"weights", weights}});
    const CpcaArrays& a = arrays(*ct);
    const Eigen::MatrixXd model = outgoing_model(a);
    // Phi is orthonormal under the view cells' equal weight, so the error the backend measures
    // in the K terms is the error of the outgoing radiance over the view cells.
    const double direct = (model - ref).norm() / ref.norm();
    EXPECT_GT(direct, 1e-3) << "5 clusters of 2 vectors reproduce 120 rows?";
    EXPECT_NEAR(a.frobenius_error, direct, 1e-6 + 1e-4 * direct);
    LocalRadiance out;
    ct->relight({"pixel", light}, out);
    EXPECT_LT(relative_error(out, model, light), 1e-5);
    // The C++ relight has no vertex subset here: a subset relight is the full one.
    EXPECT_FALSE(ct->supports_vertex_subset());
    LocalRadiance some;
    ct->relight_vertices({"pixel", light}, std::vector<std::uint32_t>{1, 7}, some);
    EXPECT_EQ(some.values, out.values);
  }
}

TEST(CpcaBrdfSignal, OpenClViewKernelMatchesTheCppRelight) {
  ClContext* ctx = default_context();
  if (ctx == nullptr) GTEST_SKIP() << "no OpenCL device";
  const TransferMatrix t = test_transfer();
  const std::vector<Rgb> light = prt::testing::pseudo_random_light(t.cols(), 4, 2.0f);
  for (const char* weights : {"float32", "float16", "s8"}) {
    SCOPED_TRACE(weights);
    const auto ct = compress(t, {{"clusters", "6"}, {"vectors", "3"}, {"weights", weights}});
    auto device = upload_compressed(*ct, *ctx);
    ASSERT_NE(device, nullptr);
    EXPECT_FALSE(device->supports_vertex_subset());
    LocalRadiance cpp, gpu;
    ct->relight({"pixel", light}, cpp);
    device->relight({"pixel", light}, gpu);
    ASSERT_EQ(gpu.values.size(), cpp.values.size());
    double se = 0, n2 = 0;
    for (std::size_t i = 0; i < cpp.values.size(); ++i)
      for (int ch = 0; ch < 3; ++ch) {
        se += std::pow(gpu.values[i][ch] - cpp.values[i][ch], 2);
        n2 += std::pow(cpp.values[i][ch], 2);
      }
    EXPECT_LT(std::sqrt(se / n2), 1e-6);
  }
}

TEST(CpcaBrdfSignal, SaveLoadKeepsTheSignalAndRefusesABadView) {
  const TransferMatrix t = test_transfer();
  const auto ct = compress(t, {{"clusters", "4"}, {"vectors", "2"}, {"brdf_roughness", "0.6"}});
  const prt::testing::TempDir dir;
  save_compressed(*ct, dir.path() / "brdf.prt");
  const auto back = load_compressed(dir.path() / "brdf.prt");
  EXPECT_EQ(arrays(*back).view_terms, 4);
  EXPECT_EQ(arrays(*back).view, arrays(*ct).view);
  const std::vector<Rgb> light = prt::testing::pseudo_random_light(t.cols(), 2, 1.0f);
  LocalRadiance a, b;
  ct->relight({"pixel", light}, a);
  back->relight({"pixel", light}, b);
  EXPECT_EQ(a.values, b.values);
  // The stored view factor is the fold's: another roughness gives another Phi.
  const auto other = compress(t, {{"clusters", "4"}, {"vectors", "2"}});
  EXPECT_NE(arrays(*other).view, arrays(*ct).view);
  EXPECT_THROW(compress(t, {{"brdf_terms", "10"}}), ParameterError);  // K > M = 9
  EXPECT_THROW(compress(t, {{"brdf_roughness", "0"}}), ParameterError);
}

}  // namespace
}  // namespace prt::cpca
