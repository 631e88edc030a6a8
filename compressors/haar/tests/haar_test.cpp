// Backend `haar`, beyond the conformance suite: the face transform against GSL's non-standard 2D
// Haar (gsl_wavelet2d_nstransform), orthonormality (Parseval, inverse(forward(x)) = x), the
// documented basis functions and their support solid angles, the area-weighted selection on a
// hand-built row, exact reconstruction with every coefficient, monotone error in k, the
// quantised relight within the bound of the quantisation step, the global budget, save/load and
// OpenCL against C++.
#include "haar/haar.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>

#ifdef PRTLAB_HAVE_GSL
#include <gsl/gsl_wavelet.h>
#include <gsl/gsl_wavelet2d.h>
#endif

#include "haar/haar_wavelet.h"
#include "haar/tests/stored_terms.h"
#include "prtlab/base/error.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/numeric/float16.h"
#include "prtlab/opencl/cl_buffer.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/storage/archive.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/transfer/random_transfer.h"
#include "support/temp_dir.h"
#include "support/test_light.h"

namespace prt::haar {
namespace {
namespace fs = std::filesystem;

const fs::path g_cache_root = prt::testing::use_private_cache("haar");

using namespace prt::haar::test_support;  // compress, arrays, stored_value, stored_index, Params

std::vector<double> random_values(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> v(n);
  for (double& x : v) x = u(rng);
  return v;
}

// supersampling 2 makes every value a multiple of 1/4, so the Haar coefficients are short dyadic
// fractions that float16 holds exactly; 3 (multiples of 1/9) makes every format round.
TransferMatrix test_transfer(int resolution = 4, std::uint64_t seed = 3, double density = 0.5,
                             int supersampling = 2) {
  return random_transfer(seed, RandomTransferSpec{12, 2, resolution, supersampling, density, {5}});
}

// Row `row` of T~ in the pixel basis, by the inverse transform of its stored terms.
std::vector<double> reconstruct_row(const HaarArrays& a, std::size_t row) {
  std::vector<double> c(static_cast<std::size_t>(a.pixel_count), 0.0);
  for (std::uint32_t i = a.offsets[row]; i < a.offsets[row + 1]; ++i)
    c[stored_index(a, i)] = stored_value(a, row, i);
  inverse_cubemap(c, a.resolution);
  return c;
}

std::vector<double> dense_row(const TransferMatrix& t, std::size_t row) {
  std::vector<double> d(t.cols(), 0.0);
  for (std::uint32_t e = t.row_offsets()[row]; e < t.row_offsets()[row + 1]; ++e)
    d[t.column(e)] = t.counts()[e] * t.scale();
  return d;
}

// ||T~ - T||_F / ||T||_F by reconstruction, in double.
double reconstructed_frobenius(const HaarArrays& a, const TransferMatrix& t) {
  double err = 0, norm = 0;
  for (std::size_t row = 0; row < t.rows(); ++row) {
    const auto x = reconstruct_row(a, row);
    const auto y = dense_row(t, row);
    for (std::size_t k = 0; k < y.size(); ++k) {
      err += (x[k] - y[k]) * (x[k] - y[k]);
      norm += y[k] * y[k];
    }
  }
  return std::sqrt(err / norm);
}

// ---- the transform ----

#ifdef PRTLAB_HAVE_GSL
TEST(HaarWavelet, ForwardAndInverseAgreeWithGslNonStandardTransform) {
  gsl_wavelet* w = gsl_wavelet_alloc(gsl_wavelet_haar, 2);
  for (int r : {1, 2, 4, 8, 32}) {
    SCOPED_TRACE(::testing::Message() << "R = " << r);
    const std::size_t n = static_cast<std::size_t>(r) * r;
    gsl_wavelet_workspace* work = gsl_wavelet_workspace_alloc(static_cast<std::size_t>(r));
    for (std::uint64_t seed : {1, 2, 3}) {
      const std::vector<double> x = random_values(n, seed + 10 * r);
      std::vector<double> ours = x, theirs = x, scratch(n);
      forward_face(ours, r, scratch);
      if (r > 1) {
        ASSERT_EQ(gsl_wavelet2d_nstransform_forward(w, theirs.data(), r, r, r, work), GSL_SUCCESS);
      }
      for (std::size_t i = 0; i < n; ++i)
        ASSERT_NEAR(ours[i], theirs[i], 1e-12) << "coefficient " << i;
      // The inverse of GSL's coefficients is ours.
      std::vector<double> back = theirs;
      inverse_face(back, r, scratch);
      if (r > 1) {
        ASSERT_EQ(gsl_wavelet2d_nstransform_inverse(w, theirs.data(), r, r, r, work), GSL_SUCCESS);
      }
      for (std::size_t i = 0; i < n; ++i) {
        ASSERT_NEAR(back[i], x[i], 1e-12);
        ASSERT_NEAR(theirs[i], x[i], 1e-12);
      }
    }
    gsl_wavelet_workspace_free(work);
  }
  gsl_wavelet_free(w);
}
#else
TEST(HaarWavelet, ForwardAndInverseAgreeWithGslNonStandardTransform) {
  GTEST_SKIP() << "built without GSL (install libgsl-dev): the comparison with "
                  "gsl_wavelet2d_nstransform is not run";
}
#endif

TEST(HaarWavelet, IsOrthonormalAndInvertible) {
  for (int r : {2, 8, 32}) {
    const std::size_t n = 6 * static_cast<std::size_t>(r) * r;
    const auto x = random_values(n, 7), y = random_values(n, 8);
    auto wx = x, wy = y;
    forward_cubemap(wx, r);
    forward_cubemap(wy, r);
    double xx = 0, wxx = 0, xy = 0, wxy = 0;
    for (std::size_t i = 0; i < n; ++i) {
      xx += x[i] * x[i];
      wxx += wx[i] * wx[i];
      xy += x[i] * y[i];
      wxy += wx[i] * wy[i];
    }
    EXPECT_NEAR(wxx, xx, 1e-10 * xx) << "Parseval at R = " << r;
    EXPECT_NEAR(wxy, xy, 1e-10 * xx) << "dot products at R = " << r;
    inverse_cubemap(wx, r);
    for (std::size_t i = 0; i < n; ++i) ASSERT_NEAR(wx[i], x[i], 1e-12);
  }
}

TEST(HaarWavelet, BasisFunctionsAreTheDocumentedBlocks) {
  const int r = 8;
  std::vector<double> face(r * r), scratch(r * r);
  for (int y = 0; y < r; ++y)
    for (int x = 0; x < r; ++x) {
      std::fill(face.begin(), face.end(), 0.0);
      face[y * r + x] = 1.0;
      inverse_face(face, r, scratch);  // the basis function of coefficient (x, y)
      const HaarSupport s = haar_support(r, x, y);
      const int h = s.size / 2;
      for (int v = 0; v < r; ++v)
        for (int u = 0; u < r; ++u) {
          const bool inside = u >= s.x0 && u < s.x0 + s.size && v >= s.y0 && v < s.y0 + s.size;
          double expected = 0;
          if (inside) {
            expected = 1.0 / s.size;
            if (s.split_x && u >= s.x0 + h) expected = -expected;
            if (s.split_y && v >= s.y0 + h) expected = -expected;
          }
          ASSERT_NEAR(face[v * r + u], expected, 1e-12)
              << "coefficient (" << x << ", " << y << ") at pixel (" << u << ", " << v << ")";
        }
    }
}

TEST(HaarWavelet, SupportSolidAnglesSumThePixelsOfTheSupport) {
  const CubemapLayout layout(4);
  const auto omega = support_solid_angles(layout);
  double faces = 0;
  for (int f = 0; f < 6; ++f) faces += omega[layout.index(f, 0, 0)];
  EXPECT_NEAR(faces, 4 * M_PI, 1e-12) << "the six scaling coefficients cover the sphere";
  // Every coefficient: the pixels where its basis function is non-zero.
  std::vector<double> basis(layout.pixel_count());
  for (int k = 0; k < layout.pixel_count(); ++k) {
    std::fill(basis.begin(), basis.end(), 0.0);
    basis[k] = 1.0;
    inverse_cubemap(basis, 4);
    double sum = 0;
    for (int p = 0; p < layout.pixel_count(); ++p)
      if (basis[p] != 0) sum += layout.solid_angle(p);
    ASSERT_NEAR(omega[k], sum, 1e-14) << "coefficient " << k;
  }
  EXPECT_THROW(support_solid_angles(CubemapLayout(6)), ParameterError);
}

TEST(HaarWavelet, TransformFlopsCountTheButterflies) {
  // R = 2: one group of 12 FLOPs per face; R = 4: 4 + 1 groups.
  EXPECT_EQ(transform_flops(1), 0.0);
  EXPECT_EQ(transform_flops(2), 6 * 12.0);
  EXPECT_EQ(transform_flops(4), 6 * 12.0 * 5);
}

// ---- selection ----

// One vertex, M = 1, R = 4 (N = 96), three faces lit:
//   face 0: 1 at pixel (0, 0). Its whole-face functions (the scaling one and the three level-1
//           differences, indices 0, 1, 4, 5) are 0.25 each, scored 0.25 x 4 pi / 6 = 0.52; the
//           2 x 2 corner block's differences (2, 8, 10) are 0.5, scored 0.5 x pi / 6 = 0.26.
//   face 1: 0.25 everywhere. Only its scaling coefficient is non-zero: 16 x 0.25 / 4 = 1
//           (index 16), scored 2.09.
//   face 2: 0.25 at pixel (0, 0): a quarter of face 0's (indices 32, 33, 36, 37 score 0.13).
// By |c| alone k = 4 would keep 16 and the three 0.5 corner terms; by area weight the
// whole-face terms win, ties going to the lower index.
TransferMatrix hand_built_row() {
  std::vector<std::uint32_t> offsets = {0}, columns;
  std::vector<std::uint8_t> counts;
  columns.push_back(0);  // face 0, pixel (0, 0): value 1 = count 4 / s^2
  counts.push_back(4);
  for (std::uint32_t k = 16; k < 32; ++k) {  // face 1: 0.25 = count 1 / s^2
    columns.push_back(k);
    counts.push_back(1);
  }
  columns.push_back(32);  // face 2, pixel (0, 0)
  counts.push_back(1);
  offsets.push_back(static_cast<std::uint32_t>(columns.size()));
  return TransferMatrix::from_csr(1, 1, 96, 2, offsets, columns, counts);
}

std::vector<std::uint32_t> kept_indices(const CompressedTransfer& ct) {
  const HaarArrays& a = arrays(ct);
  std::vector<std::uint32_t> out;
  for (std::size_t i = 0; i < a.terms(); ++i) out.push_back(stored_index(a, i));
  return out;
}

TEST(HaarSelection, AreaWeightingKeepsTheDocumentedCoefficients) {
  const TransferMatrix t = hand_built_row();
  // The coefficients as the header documents them.
  const auto row = dense_row(t, 0);
  auto c = row;
  forward_cubemap(c, 4);
  EXPECT_NEAR(c[16], 1.0, 1e-15);
  for (int i : {0, 1, 4, 5}) EXPECT_NEAR(std::abs(c[i]), 0.25, 1e-15) << i;
  for (int i : {2, 8, 10}) EXPECT_NEAR(std::abs(c[i]), 0.5, 1e-15) << i;
  const CubemapLayout layout(4);
  const auto omega = support_solid_angles(layout);
  ASSERT_LT(0.5 * omega[2], 0.25 * omega[0]) << "the hand-built case's premise";

  const auto kept = [&](const Params& p) {
    Params q = p;
    q["values"] = "float32";
    return kept_indices(*compress(t, q));
  };
  using Ids = std::vector<std::uint32_t>;
  EXPECT_EQ(kept({{"k", "3"}}), (Ids{0, 1, 16}));
  EXPECT_EQ(kept({{"k", "4"}}), (Ids{0, 1, 4, 16}));
  EXPECT_EQ(kept({{"k", "5"}}), (Ids{0, 1, 4, 5, 16}));
  EXPECT_EQ(kept({{"k", "6"}}), (Ids{0, 1, 2, 4, 5, 16}));
  // Every lit face's scaling coefficient first when they are always kept.
  EXPECT_EQ(kept({{"k", "3"}, {"scaling", "always"}}), (Ids{0, 16, 32}));
  EXPECT_EQ(kept({{"k", "4"}, {"scaling", "always"}}), (Ids{0, 1, 16, 32}));
  // At most every non-zero coefficient: 7 on face 0, 1 on face 1, 7 on face 2.
  std::size_t nonzero = 0;
  for (double v : c) nonzero += v != 0.0;
  EXPECT_EQ(nonzero, 15u);
  EXPECT_EQ(arrays(*compress(t, {{"k", "96"}, {"values", "float32"}})).terms(), nonzero);
}

TEST(HaarSelection, AllCoefficientsInFloat32ReconstructTAndRelightExactly) {
  const TransferMatrix t = test_transfer(8);
  const auto ct = compress(t, {{"k", "384"}, {"values", "float32"}});
  const HaarArrays& a = arrays(*ct);
  double worst = 0;
  for (std::size_t row = 0; row < t.rows(); ++row) {
    const auto x = reconstruct_row(a, row);
    const auto y = dense_row(t, row);
    for (std::size_t k = 0; k < y.size(); ++k) worst = std::max(worst, std::abs(x[k] - y[k]));
  }
  EXPECT_LE(worst, 1e-6) << "max |T~ - T| with every coefficient kept";
  EXPECT_EQ(a.truncation_squared_error, 0.0);
  const std::vector<Rgb> light = prt::testing::pseudo_random_light(t.cols(), 9);
  LocalRadiance out;
  ct->relight({"pixel", light}, out);
  const LocalRadiance exact = relight_exact(t, light);
  EXPECT_LE(relative_l2_error(out, exact), 1e-6);
  EXPECT_LE(max_relative_error(out, exact), 1e-6);
}

TEST(HaarSelection, ErrorFallsMonotonicallyAsKGrows) {
  const TransferMatrix t = test_transfer(8, 4, 0.6);
  double previous = 2.0;
  for (int k : {1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 64, 128, 384}) {
    SCOPED_TRACE(::testing::Message() << "k = " << k);
    const auto ct = compress(t, {{"k", std::to_string(k)}, {"values", "float32"}});
    const double measured = reconstructed_frobenius(arrays(*ct), t);
    EXPECT_NEAR(*ct->expected_frobenius_error(), measured, 1e-6 + 1e-6 * measured);
    EXPECT_LE(measured, previous + 1e-12);
    previous = measured;
  }
  EXPECT_LE(previous, 1e-6);
}

// The relight with quantised values against the relight with the kept coefficients in double:
// per row and channel, |sum_j (q_j - c_j) (W L)_j| <= sum_j e_j |(W L)_j| with e_j the format's
// bound on |q_j - c_j| (s8: half the row's step; float16: half an ulp of a half, 2^-11 |c|, or
// 2^-25 below the normal range), plus the float rounding of the sums.
TEST(HaarSelection, QuantisedRelightIsWithinTheQuantisationBound) {
  const TransferMatrix t = test_transfer(8, 5, 0.7, 3);
  const std::vector<Rgb> light = prt::testing::pseudo_random_light(t.cols(), 11);
  std::vector<double> wl[3];
  for (int ch = 0; ch < 3; ++ch) {
    wl[ch].resize(t.cols());
    for (std::size_t k = 0; k < t.cols(); ++k) wl[ch][k] = light[k][ch];
    forward_cubemap(wl[ch], 8);
  }
  for (const char* k : {"8", "384"}) {
    const auto reference = compress(t, {{"k", k}, {"values", "float32"}});
    const HaarArrays& ra = arrays(*reference);
    for (const char* format : {"float16", "s8"}) {
      SCOPED_TRACE(::testing::Message() << "k = " << k << ", " << format);
      const auto ct = compress(t, {{"k", k}, {"values", format}});
      const HaarArrays& a = arrays(*ct);
      ASSERT_EQ(a.offsets, ra.offsets);
      LocalRadiance out;
      ct->relight({"pixel", light}, out);
      int tight = 0;
      for (std::size_t row = 0; row < t.rows(); ++row) {
        for (int ch = 0; ch < 3; ++ch) {
          double kept = 0, bound = 0, magnitude = 0;
          for (std::uint32_t i = a.offsets[row]; i < a.offsets[row + 1]; ++i) {
            const double c = ra.values32[i];  // the coefficient rounded to float
            const double l = wl[ch][stored_index(a, i)];
            kept += c * l;
            const double e = a.format == ValueFormat::kS8
                                 ? 0.5 * a.row_scales[row]
                                 : std::max(std::abs(c) * 0x1p-11, 0x1p-25);
            bound += e * std::abs(l);
            magnitude += std::abs(c * l);
          }
          const double slack = 1e-6 * (magnitude + bound) + 1e-30;
          const double err = std::abs(out.values[row][ch] - kept);
          ASSERT_LE(err, bound + slack) << "row " << row << " channel " << ch;
          tight += err > 0.05 * bound;
        }
      }
      EXPECT_GT(tight, 0) << "the bound is never approached: is the quantisation applied?";
    }
  }
}

TEST(HaarSelection, GlobalBudgetKeepsTheBestScoresOfTheWholeMatrix) {
  const TransferMatrix t = test_transfer(4, 6, 0.6);
  const int k = 3;
  const auto ct = compress(
      t,
      {{"k", std::to_string(k)}, {"values", "float32"}, {"budget", "global"}, {"max_terms", "10"}});
  const HaarArrays& a = arrays(*ct);
  const CubemapLayout layout(4);
  const auto omega = support_solid_angles(layout);
  double worst_kept = INFINITY, best_dropped = 0;
  std::size_t available = 0;
  for (std::size_t row = 0; row < t.rows(); ++row) {
    auto c = dense_row(t, row);
    forward_cubemap(c, 4);
    std::vector<double> scores;
    for (std::size_t j = 0; j < c.size(); ++j)
      if (c[j] != 0) scores.push_back(std::abs(c[j]) * omega[j]);
    std::sort(scores.rbegin(), scores.rend());
    const std::size_t capped = std::min<std::size_t>(scores.size(), 10);
    available += capped;
    ASSERT_LE(a.count(row), capped);
    for (std::uint32_t i = a.offsets[row]; i < a.offsets[row + 1]; ++i) {
      const std::uint32_t j = stored_index(a, i);
      worst_kept = std::min(worst_kept, std::abs(c[j]) * omega[j]);
    }
    if (a.count(row) < capped) best_dropped = std::max(best_dropped, scores[a.count(row)]);
  }
  EXPECT_EQ(a.terms(), std::min<std::size_t>(available, k * t.rows()));
  EXPECT_GE(worst_kept, best_dropped * (1 - 1e-6)) << "a dropped term outscores a kept one";
  EXPECT_NEAR(*ct->expected_frobenius_error(), reconstructed_frobenius(a, t), 1e-9);
}

TEST(HaarSelection, StorageAndFlopsAreTheDocumentedLayout) {
  const TransferMatrix t = test_transfer(4);
  for (const char* format : {"float32", "float16", "s8"}) {
    const auto ct = compress(t, {{"k", "5"}, {"values", format}});
    const HaarArrays& a = arrays(*ct);
    const std::size_t vb =
        std::string(format) == "float32" ? 4 : (std::string(format) == "float16" ? 2 : 1);
    const std::size_t scales = std::string(format) == "s8" ? 4 * t.rows() : 0;
    EXPECT_EQ(ct->storage().total_bytes(), t.rows() * 1 + a.terms() * (2 + vb) + scales) << format;
    EXPECT_EQ(ct->flops_per_relight(),
              transform_flops(4) + 2.0 * a.terms() + (scales ? double(t.rows()) : 0.0));
    for (std::size_t row = 0; row < t.rows(); ++row) ASSERT_LE(a.count(row), 5u);
  }
  const auto wide = compress(t, {{"k", "5"}, {"index", "u32"}});
  EXPECT_TRUE(arrays(*wide).wide);
  EXPECT_EQ(wide->storage().total_bytes(), t.rows() * 5 + arrays(*wide).terms() * 5);
}

TEST(HaarSelection, RejectsANonPowerOfTwoCubemap) {
  const TransferMatrix t = random_transfer(1, RandomTransferSpec{3, 2, 3, 2, 0.5, {}});
  try {
    (void)compress(t, {});
    FAIL() << "R = 3 accepted";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("power of two"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("haar"), std::string::npos) << e.what();
  }
}

// ---- save/load and the device ----

const std::vector<Params> kVariants = {
    {{"values", "float32"}, {"k", "7"}},
    {{"values", "float16"}, {"k", "7"}},
    {{"values", "s8"}, {"k", "7"}},
    {{"values", "s8"}, {"k", "300"}, {"index", "u32"}},
    {{"values", "float16"}, {"k", "4"}, {"budget", "global"}, {"scaling", "always"}},
};

std::string describe(const Params& p) {
  std::string s;
  for (const auto& [k, v] : p) s += k + "=" + v + " ";
  return s;
}

TEST(Haar, SaveLoadRoundTripsEveryVariant) {
  const TransferMatrix t = test_transfer(8);
  const std::vector<Rgb> light = prt::testing::pseudo_random_light(t.cols(), 4);
  prt::testing::TempDir dir("haar-save");
  for (const Params& p : kVariants) {
    SCOPED_TRACE(describe(p));
    const auto ct = compress(t, p);
    const fs::path file = dir.path() / "h.prtc";
    save_compressed(*ct, file);
    const auto back = load_compressed(file);
    const HaarArrays& a = arrays(*ct);
    const HaarArrays& b = arrays(*back);
    EXPECT_EQ(a.offsets, b.offsets);
    EXPECT_EQ(a.indices16, b.indices16);
    EXPECT_EQ(a.indices32, b.indices32);
    EXPECT_EQ(a.codes, b.codes);
    EXPECT_EQ(a.row_scales, b.row_scales);
    EXPECT_EQ(a.values16, b.values16);
    EXPECT_EQ(a.values32, b.values32);
    EXPECT_EQ(ct->expected_frobenius_error(), back->expected_frobenius_error());
    LocalRadiance x, y;
    ct->relight({"pixel", light}, x);
    back->relight({"pixel", light}, y);
    EXPECT_EQ(std::memcmp(x.values.data(), y.values.data(), x.values.size() * sizeof(Rgb)), 0);
  }
}

TEST(Haar, OpenClMatchesTheCppRelight) {
  ClContext* ctx = default_context();
  if (ctx == nullptr) GTEST_SKIP() << "no OpenCL device";
  for (int r : {4, 16}) {
    const TransferMatrix t = test_transfer(r, 8, 0.4);
    const std::vector<Rgb> light = prt::testing::pseudo_random_light(t.cols(), 5);
    const std::vector<std::uint32_t> subset = {0, 3, 4, 11};
    for (Params p : kVariants) {
      SCOPED_TRACE(::testing::Message() << "R = " << r << " " << describe(p));
      const auto ct = compress(t, p);
      auto device = upload_compressed(*ct, *ctx);
      ASSERT_NE(device, nullptr);
      LocalRadiance cpp, gpu;
      ct->relight({"pixel", light}, cpp);
      device->relight({"pixel", light}, gpu);
      EXPECT_LE(max_relative_error(gpu, cpp), 1e-5);
      // The subset kernel gives the subset's rows the full kernel's bits.
      device->set_vertex_subset(subset);
      EXPECT_GE(device->relight_subset_on_device({"pixel", light}), 0.0);
      std::vector<Rgb> after(gpu.values.size());
      download(*ctx, device->output_buffer(), std::span<Rgb>(after), "haar test output");
      const std::size_t m = t.local_count();
      for (std::uint32_t v : subset)
        for (std::size_t j = 0; j < m; ++j)
          ASSERT_EQ(std::memcmp(&after[v * m + j], &gpu.values[v * m + j], sizeof(Rgb)), 0);
    }
  }
}

TEST(Haar, VertexSubsetRelightHasTheFullRelightsBits) {
  const TransferMatrix t = test_transfer(4);
  const std::vector<Rgb> light = prt::testing::pseudo_random_light(t.cols(), 6);
  const std::vector<std::uint32_t> subset = {1, 2, 7, 11};
  for (const Params& p : kVariants) {
    const auto ct = compress(t, p);
    LocalRadiance full, part;
    ct->relight({"pixel", light}, full);
    ct->relight_vertices({"pixel", light}, subset, part);
    const std::size_t m = t.local_count();
    for (std::uint32_t v : subset)
      for (std::size_t j = 0; j < m; ++j)
        ASSERT_EQ(std::memcmp(&full.values[v * m + j], &part.values[v * m + j], sizeof(Rgb)), 0);
  }
}

}  // namespace
}  // namespace prt::haar
