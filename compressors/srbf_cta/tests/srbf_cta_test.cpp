// Backend `srbf_cta`, beyond the conformance suite: the clustered tensor approximation reproduces
// an exactly low-rank clustered tensor, agrees with vmmlib's Tucker decomposition (HOSVD / HOOI)
// on one cluster, never raises its error and ends with every vertex in its best cluster; the
// backend's stored errors against a dense recomputation, full-rank CTA is exactly the SRBF
// projection, the pixel-quadrature relight equals the dense product T~ L, uniform light on the
// transfer SRBFs equals it up to the ridge, save/load, and OpenCL against C++; on the
// BRDF-weighted signal, the stored errors against a dense recomputation from the folded transfer
// and, at full rank, against an independent projection of the folded rows.
#include "srbf_cta/srbf_cta.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <cmath>
#include <filesystem>
#include <random>

#include "prtlab/base/error.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/transfer_error.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/storage/archive.h"
#include "prtlab/transfer/brdf_weighted_transfer.h"
#include "prtlab/transfer/random_transfer.h"
#include "prtlab/transfer/transfer_matrix.h"
#include "srbf_cta/cluster_unfolding.h"
#include "srbf_cta/clustered_tensor.h"
#include "srbf_cta/cta_checkpoint.h"
#include "support/temp_dir.h"
#include "support/test_light.h"

#ifdef PRTLAB_HAVE_VMMLIB
#include "srbf_cta/tests/vmmlib_tucker.h"
#endif

namespace prt::srbf_cta {
namespace {
namespace fs = std::filesystem;

const fs::path g_cache_root = prt::testing::use_private_cache("srbf_cta");

Eigen::MatrixXd random_orthonormal(Eigen::Index rows, Eigen::Index cols, std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  Eigen::MatrixXd a(rows, cols);
  for (Eigen::Index i = 0; i < a.size(); ++i) a.data()[i] = g(rng);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(a);
  return qr.householderQ() * Eigen::MatrixXd::Identity(rows, cols);
}

struct Tensor {
  std::vector<float> values;
  std::size_t vertices, view, light;
  TensorView view_of() const { return {values, vertices, view, light}; }
  double squared_norm() const {
    double s = 0;
    for (float v : values) s += static_cast<double>(v) * v;
    return s;
  }
};

// Clusters of vertices, each exactly X_x = U (sum_j w_xj B_cj) U_c^T with a shared U (i1 x r1),
// per cluster U_c (i2 x r2) and r3 core slices B_cj: Tucker rank (r1, r2, r3) per cluster.
Tensor clustered_low_rank(std::size_t clusters, std::size_t per_cluster, int i1, int i2, int r1,
                          int r2, int r3, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  const Eigen::MatrixXd u = random_orthonormal(i1, r1, rng);
  Tensor t{{}, clusters * per_cluster, static_cast<std::size_t>(i1), static_cast<std::size_t>(i2)};
  for (std::size_t c = 0; c < clusters; ++c) {
    const Eigen::MatrixXd uc = random_orthonormal(i2, r2, rng);
    std::vector<Eigen::MatrixXd> b(static_cast<std::size_t>(r3));
    for (auto& bj : b) bj = Eigen::MatrixXd::NullaryExpr(r1, r2, [&] { return g(rng); });
    for (std::size_t k = 0; k < per_cluster; ++k) {
      Eigen::MatrixXd core = Eigen::MatrixXd::Zero(r1, r2);
      for (auto& bj : b) core += (1.0 + g(rng)) * bj;
      const Eigen::MatrixXd x = u * core * uc.transpose();
      for (int i = 0; i < i1; ++i)
        for (int j = 0; j < i2; ++j) t.values.push_back(static_cast<float>(x(i, j)));
    }
  }
  return t;
}

Tensor random_tensor(std::size_t vertices, int i1, int i2, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> g;
  Tensor t{{}, vertices, static_cast<std::size_t>(i1), static_cast<std::size_t>(i2)};
  t.values.resize(vertices * static_cast<std::size_t>(i1 * i2));
  for (float& v : t.values) v = g(rng);
  return t;
}

double direct_squared_error(const Tensor& t, const CtaModel& m) {
  double e = 0;
  for (std::size_t x = 0; x < t.vertices; ++x) {
    const RowMajorMatrixXd r = reconstruct_vertex(m, x);
    for (std::size_t i = 0; i < t.view; ++i)
      for (std::size_t j = 0; j < t.light; ++j) {
        const double d = r(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) -
                         t.values[(x * t.view + i) * t.light + j];
        e += d * d;
      }
  }
  return e;
}

TEST(ClusteredTensor, ReproducesAnExactlyLowRankClusteredTensor) {
  const Tensor t = clustered_low_rank(3, 30, 6, 20, 3, 4, 2, 17);
  CtaOptions o;
  o.clusters = 3;
  o.rank_view = 3;
  o.rank_light = 4;
  o.rank_vertex = 2;
  const CtaModel m = clustered_tensor_approximation(t.view_of(), o);
  const double rel = std::sqrt(direct_squared_error(t, m) / t.squared_norm());
  EXPECT_LT(rel, 1e-5);
  // The model's own total is ||X||^2 - ||W||^2: exact to the rounding of the float products.
  EXPECT_LT(m.squared_error / m.total_squared_norm, 1e-7);
  // Each true cluster ends in one cluster of the model.
  for (std::size_t c = 0; c < 3; ++c)
    for (std::size_t k = 1; k < 30; ++k)
      EXPECT_EQ(m.assignments[c * 30 + k], m.assignments[c * 30]) << "cluster " << c;
  // One rank short in the light mode, the same tensor cannot be exact.
  o.rank_light = 3;
  const CtaModel short_rank = clustered_tensor_approximation(t.view_of(), o);
  EXPECT_GT(std::sqrt(short_rank.squared_error / short_rank.total_squared_norm), 1e-2);
}

TEST(ClusteredTensor, VertexModeOfALargeClusterIsTheTruncatedSvdOfItsUnfolding) {
  // One cluster of 600 vertices with full view and light ranks: the bases are rotations, so the
  // error is the tail of the singular values of the 600 x 640 vertex unfolding. 600 members
  // take the Lanczos path of the vertex Gram matrix; the spectrum has a gap after the 24 kept.
  const Eigen::Index m = 600, i1 = 8, i2 = 80, rank = 100, kept = 24;
  std::mt19937_64 rng(5);
  const Eigen::MatrixXd a = random_orthonormal(m, rank, rng);
  const Eigen::MatrixXd b = random_orthonormal(i1 * i2, rank, rng);
  Eigen::VectorXd s(rank);
  for (Eigen::Index j = 0; j < rank; ++j)
    s[j] = j < kept ? 2.0 * std::pow(0.97, j) : 0.1 * std::pow(0.99, j);
  const RowMajorMatrixXd x = a * s.asDiagonal() * b.transpose();
  Tensor t{
      {}, static_cast<std::size_t>(m), static_cast<std::size_t>(i1), static_cast<std::size_t>(i2)};
  for (Eigen::Index i = 0; i < x.size(); ++i) t.values.push_back(static_cast<float>(x.data()[i]));
  Eigen::MatrixXd xf(m, i1 * i2);
  for (Eigen::Index i = 0; i < xf.rows(); ++i)
    for (Eigen::Index j = 0; j < xf.cols(); ++j)
      xf(i, j) = t.values[static_cast<std::size_t>(i * xf.cols() + j)];
  const Eigen::VectorXd sv = Eigen::BDCSVD<Eigen::MatrixXd>(xf).singularValues();
  const double tail = sv.tail(sv.size() - kept).squaredNorm();

  CtaOptions o;
  o.clusters = 1;
  o.rank_light = static_cast<int>(i2);
  o.rank_vertex = static_cast<int>(kept);
  o.clustering_iterations = 0;
  const CtaModel model = clustered_tensor_approximation(t.view_of(), o);
  ASSERT_EQ(model.clusters.size(), 1u);
  const RowMajorMatrixXd& dual = model.clusters[0].dual;
  ASSERT_EQ(dual.rows(), kept);
  EXPECT_LT((dual * dual.transpose() - Eigen::MatrixXd::Identity(kept, kept)).norm(), 1e-10);
  const double tol = 1e-6 * model.total_squared_norm;
  EXPECT_NEAR(model.squared_error, tail, tol);
  EXPECT_NEAR(direct_squared_error(t, model), tail, tol);
}

TEST(ClusterUnfolding, SubspaceIterationFindsTheTruncatedSvdInBothRepresentations) {
  // 300 members, Y 300 x (6 x 10): the subspace path (m > twice the block of 12 + 8 vectors).
  // Its captured energy (the squared norm of the double-precision weights) must be the top
  // singular values' of a dense SVD of Y, formed (double) or applied through Z (float products).
  const Eigen::Index m = 300, r1 = 6, i2 = 30, r2 = 10, rank = 12;
  std::mt19937_64 rng(17);
  std::normal_distribution<double> g;
  std::vector<float> z(static_cast<std::size_t>(m * r1 * i2));
  // A decaying spectrum over the members, so that the top 12 are well separated.
  const Eigen::MatrixXd basis = random_orthonormal(r1 * i2, 40, rng);
  for (Eigen::Index x = 0; x < m; ++x) {
    Eigen::VectorXd c(40);
    for (Eigen::Index j = 0; j < 40; ++j) c[j] = g(rng) * std::pow(0.8, static_cast<double>(j));
    const Eigen::VectorXd v = basis * c;
    for (Eigen::Index i = 0; i < r1 * i2; ++i)
      z[static_cast<std::size_t>(x * r1 * i2 + i)] = static_cast<float>(v[i]);
  }
  std::vector<std::uint32_t> members;
  for (Eigen::Index x = m - 1; x >= 0; --x) members.push_back(static_cast<std::uint32_t>(x));
  const Eigen::MatrixXd light = random_orthonormal(i2, r2, rng);
  // Y densely, in double, from the float Z.
  Eigen::MatrixXd y(m, r1 * r2);
  for (Eigen::Index k = 0; k < m; ++k) {
    Eigen::MatrixXd zx(r1, i2);
    for (Eigen::Index a = 0; a < r1; ++a)
      for (Eigen::Index b = 0; b < i2; ++b)
        zx(a, b) =
            z[static_cast<std::size_t>((members[static_cast<std::size_t>(k)] * r1 + a) * i2 + b)];
    const RowMajorMatrixXd p = zx * light;
    y.row(k) = Eigen::Map<const Eigen::RowVectorXd>(p.data(), r1 * r2);
  }
  const Eigen::VectorXd sv = Eigen::BDCSVD<Eigen::MatrixXd>(y).singularValues();
  const double top = sv.head(rank).squaredNorm();
  using R = ClusterUnfolding::Representation;
  for (const R rep : {R::kFormed, R::kImplicit}) {
    const ClusterUnfolding u(z.data(), r1, i2, members, light, rank + 8, 8, rep);
    ASSERT_EQ(u.formed(), rep == R::kFormed);
    VertexModeOptions o;
    o.rank = rank;
    const VertexMode vm = top_vertex_mode(u, o, nullptr, nullptr);
    EXPECT_GT(vm.iterations, 0);
    ASSERT_EQ(vm.v.cols(), rank);
    EXPECT_LT((vm.v.transpose() * vm.v - Eigen::MatrixXd::Identity(rank, rank)).norm(), 1e-12);
    // The weights are Y v whatever the iteration's precision (formed, Y is the float product
    // Z_x U_c, as the model always formed it).
    EXPECT_LT((vm.weights - y * vm.v).norm(), (rep == R::kFormed ? 1e-6 : 1e-9) * y.norm());
    const double tol = rep == R::kFormed ? 1e-6 : 1e-5;
    EXPECT_NEAR(vm.weights.squaredNorm(), top, tol * top)
        << (rep == R::kFormed ? "formed" : "implicit");
    for (Eigen::Index j = 0; j < rank; ++j) EXPECT_NEAR(vm.sigma[j], sv[j], 1e-4 * sv[0]);
    // Started from its own answer, one iteration keeps it (Rayleigh-Ritz over a span holding it).
    const Eigen::MatrixXd start = vm.v;
    const VertexMode again = top_vertex_mode(u, o, &start, nullptr);
    EXPECT_GE(again.weights.squaredNorm(), vm.weights.squaredNorm() * (1 - 1e-6));
    EXPECT_LE(again.iterations, 3);
  }
}

// A CTA of a small random tensor whose clusters still take the subspace iteration.
CtaOptions small_cta(int clusters, int rank_light, int rank_vertex, int iterations) {
  CtaOptions o;
  o.clusters = clusters;
  o.rank_light = rank_light;
  o.rank_vertex = rank_vertex;
  o.clustering_iterations = iterations;
  o.elbg_dims = 16;
  return o;
}

TEST(ClusteredTensor, SameModelOnOneAndOnTwoThreads) {
  // Clusters large enough for the subspace iteration; every reduction is over fixed blocks, so
  // the thread count must not move a bit of the model.
  const Tensor t = random_tensor(500, 6, 40, 23);
  const CtaOptions o = small_cta(3, 12, 6, 3);
  CtaModel one, two;
  tbb::task_arena(1).execute([&] { one = clustered_tensor_approximation(t.view_of(), o); });
  tbb::task_arena(2).execute([&] { two = clustered_tensor_approximation(t.view_of(), o); });
  EXPECT_EQ(one.squared_error, two.squared_error);
  EXPECT_EQ(one.assignments, two.assignments);
  EXPECT_EQ((one.weights - two.weights).cwiseAbs().maxCoeff(), 0.0);
}

TEST(ClusteredTensor, ResumedRunEndsWithTheUninterruptedModel) {
  // The checkpoint after the first clustering iteration, through an archive and back, then run
  // to the end: the same model as the run that was never stopped.
  const Tensor t = random_tensor(300, 6, 30, 29);
  CtaOptions o = small_cta(4, 10, 5, 4);
  std::vector<std::vector<std::byte>> saved;
  std::vector<int> iterations;
  o.on_checkpoint = [&](const CtaCheckpoint& c) {
    saved.push_back(save_cta_checkpoint(c).to_bytes());
    iterations.push_back(c.model.clustering_iterations);
  };
  const CtaModel whole = clustered_tensor_approximation(t.view_of(), o);
  ASSERT_GE(saved.size(), 2u);
  EXPECT_EQ(iterations.front(), 0);  // after the initialisation
  for (std::size_t k = 0; k < saved.size(); ++k) {
    const CtaCheckpoint c =
        load_cta_checkpoint(ArchiveReader::from_bytes(saved[k], "checkpoint.prt"));
    CtaOptions r = o;
    r.on_checkpoint = nullptr;
    r.resume = &c;
    const CtaModel resumed = clustered_tensor_approximation(t.view_of(), r);
    EXPECT_EQ(resumed.squared_error, whole.squared_error) << "from checkpoint " << k;
    EXPECT_EQ(resumed.assignments, whole.assignments) << "from checkpoint " << k;
    EXPECT_EQ(resumed.clustering_iterations, whole.clustering_iterations);
    EXPECT_EQ((resumed.weights - whole.weights).cwiseAbs().maxCoeff(), 0.0);
  }
  // A checkpoint archive without its shapes is an InputError naming it, never a crash.
  ArchiveWriter broken("srbf_cta-checkpoint", 1);
  broken.add_meta("view", 6);
  const std::vector<std::byte> bytes = broken.to_bytes();
  EXPECT_THROW(load_cta_checkpoint(ArchiveReader::from_bytes(bytes, "broken.prt")), InputError);
  // A checkpoint of other ranks is refused, never silently used.
  const CtaCheckpoint c = load_cta_checkpoint(ArchiveReader::from_bytes(saved[0], "c.prt"));
  CtaOptions other = o;
  other.rank_vertex = 4;
  other.resume = &c;
  EXPECT_THROW(clustered_tensor_approximation(t.view_of(), other), ParameterError);
}

TEST(ClusteredTensor, ErrorNeverIncreasesAndEveryVertexEndsInItsBestCluster) {
  // Three planted clusters plus noise, clustered into five with too small ranks: vertices move.
  Tensor t = clustered_low_rank(3, 40, 5, 16, 4, 6, 4, 3);
  std::mt19937_64 rng(9);
  std::normal_distribution<float> g;
  for (float& v : t.values) v += 0.3f * g(rng);
  for (int r1 : {5, 3}) {
    CtaOptions o;
    o.clusters = 5;
    o.rank_view = r1;
    o.rank_light = 3;
    o.rank_vertex = 2;
    o.clustering_iterations = 50;
    o.clustering_tolerance = 0;  // until no vertex moves: every vertex in its best cluster
    o.approximation_iterations = 10;
    o.tolerance = 0;
    const CtaModel m = clustered_tensor_approximation(t.view_of(), o);
    const double tol = 1e-6 * m.total_squared_norm;
    ASSERT_FALSE(m.refit_errors.empty());
    // Clustering: refit, (before, after) reclassification, refit, ...; then approximation refits.
    std::vector<double> chain{m.refit_errors[0]};
    for (std::size_t i = 0; i * 2 < m.reclassification_errors.size(); ++i) {
      chain.push_back(m.reclassification_errors[2 * i]);
      chain.push_back(m.reclassification_errors[2 * i + 1]);
      if (i + 1 < m.refit_errors.size()) chain.push_back(m.refit_errors[i + 1]);
    }
    for (std::size_t i = m.reclassification_errors.size() / 2 + 1; i < m.refit_errors.size(); ++i)
      chain.push_back(m.refit_errors[i]);
    for (std::size_t i = 1; i < chain.size(); ++i)
      EXPECT_LE(chain[i], chain[i - 1] + tol) << "rank_view " << r1 << ", step " << i;
    EXPECT_GE(m.clustering_iterations, 2) << "no vertex moved: the test exercises nothing";
    EXPECT_NEAR(direct_squared_error(t, m), m.squared_error, tol);
    if (r1 == 5) {
      // Converged with U a rotation: no refit after the last classification, so every vertex
      // sits in the cluster whose bases approximate it best (eq. 18).
      ASSERT_LT(m.clustering_iterations, o.clustering_iterations);
      EXPECT_EQ(m.approximation_iterations, 0);
      for (std::size_t x = 0; x < t.vertices; ++x) {
        const double own = vertex_cluster_error(t.view_of(), m, x, m.assignments[x]);
        for (std::size_t c = 0; c < m.clusters.size(); ++c) {
          if (m.clusters[c].members.empty()) continue;
          EXPECT_LE(own, vertex_cluster_error(t.view_of(), m, x, c) + 1e-6 * own + 1e-12)
              << "vertex " << x << " would be better in cluster " << c;
        }
      }
    } else {
      EXPECT_GE(m.approximation_iterations, 1);
    }
  }
}

TEST(ClusteredTensor, OneClusterAgreesWithVmmlibTucker) {
#ifndef PRTLAB_HAVE_VMMLIB
  GTEST_SKIP() << "vmmlib not found at configure time (Debian libvmmlib-dev, liblapack-dev, "
                  "libblas-dev)";
#else
  constexpr std::size_t I1 = 6, I2 = 7, I3 = 8, R1 = 2, R2 = 3, R3 = 2;
  int agree = 0;
  for (std::uint64_t seed : {1, 2, 3, 4, 5}) {
    const Tensor t = random_tensor(I3, I1, I2, seed);
    // vmmlib's layout: x(i, j, k) at i + I1 (j + I2 k), k the vertex.
    std::vector<double> x(I1 * I2 * I3);
    for (std::size_t k = 0; k < I3; ++k)
      for (std::size_t i = 0; i < I1; ++i)
        for (std::size_t j = 0; j < I2; ++j)
          x[i + I1 * (j + I2 * k)] = t.values[(k * I1 + i) * I2 + j];
    const test::VmmlibTuckerErrors ref = test::vmmlib_tucker_errors<I1, I2, I3, R1, R2, R3>(x);
    CtaOptions o;
    o.clusters = 1;
    o.rank_view = R1;
    o.rank_light = R2;
    o.rank_vertex = R3;
    o.hooi_sweeps = 3;
    o.approximation_iterations = 200;
    o.tolerance = 1e-12;
    const CtaModel m = clustered_tensor_approximation(t.view_of(), o);
    const double ours = std::sqrt(m.squared_error / m.total_squared_norm);
    EXPECT_NEAR(ours, std::sqrt(direct_squared_error(t, m) / t.squared_norm()), 1e-6);
    // HOOI from HOSVD on both sides: the same fixed point (vmmlib stops at a fit change of 1e-4
    // and computes its products in float).
    // Never meaningfully worse than vmmlib's HOOI; the same fixed point on most tensors (vmmlib
    // stops after 10 sweeps or a fit change below 1e-4, so it may stop short where we go on).
    EXPECT_LE(ours, ref.hooi * (1 + 1e-3)) << "seed " << seed;
    agree += std::abs(ours - ref.hooi) <= 2e-3 * ref.hooi;
    EXPECT_LE(ours, ref.hosvd + 1e-6) << "seed " << seed;
  }
  EXPECT_GE(agree, 4) << "the N-mode SVD and vmmlib's HOOI agree on fewer than 4 of 5 tensors";
#endif
}

TEST(ClusteredTensor, RejectsBadInput) {
  const Tensor t = random_tensor(4, 3, 5, 1);
  CtaOptions o;
  o.rank_light = 0;
  EXPECT_THROW(clustered_tensor_approximation(t.view_of(), o), ParameterError);
  o.rank_light = 2;
  TensorView bad = t.view_of();
  bad.vertices = 5;
  EXPECT_THROW(clustered_tensor_approximation(bad, o), ParameterError);
  Tensor nan = t;
  nan.values[3] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(clustered_tensor_approximation(nan.view_of(), o), ParameterError);
}

// ---- the backend -----------------------------------------------------------------------------

using Params = std::map<std::string, std::string>;

// 24 vertices, M = 4, N = 96 (R = 4).
TransferMatrix test_transfer(std::uint64_t seed = 5) {
  return random_transfer(seed, RandomTransferSpec{24, 2, 4, 4, 0.3, {3}});
}

std::unique_ptr<CompressedTransfer> compress(const TransferMatrix& t, Params p) {
  const CubemapLayout cubemap(static_cast<int>(std::lround(std::sqrt(t.cols() / 6.0))));
  const HemisphereGrid grid(static_cast<int>(std::lround(std::sqrt(t.local_count()))));
  p.emplace("srbfs", "42");
  return CompressorRegistry::instance()
      .create(std::string(kName), p)
      ->compress({t, nullptr, cubemap, grid}, Progress::null());
}

const SrbfCtaArrays& arrays(const CompressedTransfer& ct) {
  return dynamic_cast<const SrbfCtaTransfer&>(ct).arrays();
}

Eigen::MatrixXd dense(const TransferMatrix& t) {
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(t.rows()),
                                            static_cast<Eigen::Index>(t.cols()));
  for (std::size_t r = 0; r < t.rows(); ++r)
    for (std::uint32_t e = t.row_offsets()[r]; e < t.row_offsets()[r + 1]; ++e)
      d(static_cast<Eigen::Index>(r), t.column(e)) = t.value(e);
  return d;
}

// G (N x n_t): the transfer SRBFs at the pixel centres, from srbf_eval directly.
Eigen::MatrixXd pixel_values(const SrbfCtaArrays& a) {
  const CubemapLayout layout(static_cast<int>(std::lround(std::sqrt(a.pixel_count / 6.0))));
  const SrbfBasis b = transfer_basis(a.srbf_count, a.bandwidth);
  Eigen::MatrixXd g(a.pixel_count, a.srbf_count);
  for (int k = 0; k < a.pixel_count; ++k)
    for (int j = 0; j < a.srbf_count; ++j)
      g(k, j) = srbf_eval(b.kernel, glm::dot(layout.direction(k), b.centres[j]), b.bandwidths[j]);
  return g;
}

// T~ in the pixel basis from the stored arrays, by the paper's eq. 18 written out.
Eigen::MatrixXd reconstructed(const SrbfCtaArrays& a) {
  const Eigen::MatrixXd g = pixel_values(a);
  const int r1 = a.rank_view, r2 = a.rank_light, r3 = a.rank_vertex, nt = a.srbf_count,
            m = a.local_count;
  Eigen::MatrixXd out(static_cast<Eigen::Index>(a.vertices) * m, a.pixel_count);
  for (std::size_t x = 0; x < a.vertices; ++x) {
    const std::size_t c = a.ids[x];
    Eigen::MatrixXd k = Eigen::MatrixXd::Zero(r1, r2);
    for (int j = 0; j < r3; ++j)
      for (int ia = 0; ia < r1; ++ia)
        for (int b = 0; b < r2; ++b)
          k(ia, b) += a.weights[x * r3 + j] * a.duals[((c * r3 + j) * r1 + ia) * r2 + b];
    Eigen::MatrixXd u(m, r1), uc(nt, r2);
    for (int i = 0; i < m; ++i)
      for (int ia = 0; ia < r1; ++ia) u(i, ia) = a.view_basis[i * r1 + ia];
    for (int l = 0; l < nt; ++l)
      for (int b = 0; b < r2; ++b) uc(l, b) = a.light_bases[(c * nt + l) * r2 + b];
    out.middleRows(static_cast<Eigen::Index>(x) * m, m) = u * k * uc.transpose() * g.transpose();
  }
  return out;
}

Cubemap random_radiance(int resolution, std::uint64_t seed) {
  Cubemap c(resolution);
  const std::vector<Rgb> v = prt::testing::pseudo_random_light(c.radiance.size(), seed, 2.0f);
  std::copy(v.begin(), v.end(), c.radiance.begin());
  return c;
}

TEST(SrbfCta, StoredErrorsMatchADenseRecomputation) {
  const TransferMatrix t = test_transfer();
  const Eigen::MatrixXd td = dense(t);
  for (const char* precision : {"float32", "float16"}) {
    const auto ct = compress(t, {{"clusters", "3"},
                                 {"rank_light", "6"},
                                 {"rank_vertex", "3"},
                                 {"precision", precision},
                                 {"light", "pixel"}});
    const SrbfCtaArrays& a = arrays(*ct);
    const double direct = (reconstructed(a) - td).norm() / td.norm();
    EXPECT_NEAR(a.frobenius_error, direct, 1e-5) << precision;
    ASSERT_TRUE(ct->expected_frobenius_error().has_value());
    EXPECT_GT(a.frobenius_error, a.srbf_frobenius_error) << "CTA at low rank loses nothing?";
  }
}

TEST(SrbfCta, FullRankCtaIsExactlyTheSrbfProjection) {
  const TransferMatrix t = test_transfer();
  // One cluster, every SRBF, vertex rank = the vertex count: CTA keeps the tensor whole.
  const auto ct = compress(t, {{"clusters", "1"},
                               {"rank_light", "42"},
                               {"rank_vertex", "24"},
                               {"precision", "float32"},
                               {"light", "pixel"}});
  const SrbfCtaArrays& a = arrays(*ct);
  EXPECT_NEAR(a.frobenius_error, a.srbf_frobenius_error, 1e-5);
  // The SRBF projection itself, independently: each row by regularised least squares.
  const CubemapLayout layout(4);
  const SrbfProjector p(transfer_basis(42, a.bandwidth), layout, a.ridge);
  const Eigen::MatrixXd g = pixel_values(a);
  const Eigen::MatrixXd td = dense(t);
  double se = 0;
  for (std::size_t r = 0; r < t.rows(); ++r) {
    std::vector<std::uint32_t> cols;
    std::vector<double> vals;
    for (std::uint32_t e = t.row_offsets()[r]; e < t.row_offsets()[r + 1]; ++e) {
      cols.push_back(t.column(e));
      vals.push_back(t.value(e));
    }
    const Eigen::VectorXd c = p.project_sparse(cols, vals);
    se += (g * c - td.row(static_cast<Eigen::Index>(r)).transpose()).squaredNorm();
  }
  EXPECT_NEAR(a.srbf_frobenius_error, std::sqrt(se) / td.norm(), 1e-6);
}

// The declared error is the one the relight's own light step implies: with uniform light the
// stored model through the light SRBFs' fit and eq. 13, measured by relighting every column;
// scattered light depends on the light non-linearly and declares none.
TEST(SrbfCta, DeclaredErrorIsTheRelightsOperatorsForEveryLinearLightMode) {
  const TransferMatrix t = test_transfer();
  const Params base{{"clusters", "3"}, {"rank_light", "8"}, {"rank_vertex", "3"}};
  for (const char* light : {"uniform", "pixel"}) {
    Params p = base;
    p["light"] = light;
    const auto ct = compress(t, p);
    ASSERT_TRUE(ct->expected_frobenius_error().has_value()) << light;
    const FrobeniusError f = frobenius_error(*ct, t, HemisphereGrid(2));
    ASSERT_TRUE(f.exact);
    EXPECT_NEAR(f.relative, *ct->expected_frobenius_error(), 1e-5) << light;
  }
  Params scattered = base;
  scattered["light"] = "scattered";
  EXPECT_FALSE(compress(t, scattered)->expected_frobenius_error().has_value());
}

TEST(SrbfCta, PixelLightRelightIsTheDenseProductAndUniformLightAgrees) {
  const TransferMatrix t = test_transfer();
  const Cubemap radiance = random_radiance(4, 3);
  const std::vector<Rgb> lv = radiance.light_vector();
  Eigen::MatrixXd l(96, 3);
  for (int k = 0; k < 96; ++k)
    for (int ch = 0; ch < 3; ++ch) l(k, ch) = lv[static_cast<std::size_t>(k)][ch];
  const Params base{{"clusters", "3"}, {"rank_light", "8"}, {"rank_vertex", "3"}};
  Params pixel = base;
  pixel["light"] = "pixel";
  const auto ct = compress(t, pixel);
  const Eigen::MatrixXd expect = reconstructed(arrays(*ct)) * l;
  LocalRadiance out;
  ct->relight(ct->project_light(radiance), out);
  double se = 0;
  for (Eigen::Index r = 0; r < expect.rows(); ++r)
    for (int ch = 0; ch < 3; ++ch) {
      const double d = out.values[static_cast<std::size_t>(r)][ch] - expect(r, ch);
      se += d * d;
    }
  EXPECT_LT(std::sqrt(se) / expect.norm(), 1e-5);
  // Uniform light on the transfer SRBFs: A (A + alpha I)^-1 b = b up to the ridge.
  const auto cu = compress(t, base);
  const LightCoeffs lp = ct->project_light(radiance), lu = cu->project_light(radiance);
  ASSERT_EQ(lp.values.size(), lu.values.size());
  EXPECT_EQ(lu.basis, "srbf42");
  double diff = 0, norm = 0;
  for (std::size_t j = 0; j < lp.values.size(); ++j)
    for (int ch = 0; ch < 3; ++ch) {
      diff += std::pow(lp.values[j][ch] - lu.values[j][ch], 2);
      norm += std::pow(lp.values[j][ch], 2);
    }
  EXPECT_LT(std::sqrt(diff / norm), 1e-4);
  EXPECT_GT(std::sqrt(diff / norm), 0.0);
}

TEST(SrbfCta, SaveLoadAndOpenClAgree) {
  const TransferMatrix t = test_transfer();
  const auto ct = compress(t, {{"clusters", "4"}, {"rank_light", "6"}, {"rank_vertex", "3"}});
  const Cubemap radiance = random_radiance(4, 8);
  const LightCoeffs light = ct->project_light(radiance);
  LocalRadiance cpu;
  ct->relight(light, cpu);
  const prt::testing::TempDir dir;
  const fs::path file = dir.path() / "cta.prt";
  save_compressed(*ct, file);
  const auto back = load_compressed(file);
  LocalRadiance again;
  back->relight(back->project_light(radiance), again);
  ASSERT_EQ(again.values.size(), cpu.values.size());
  for (std::size_t i = 0; i < cpu.values.size(); ++i)
    for (int ch = 0; ch < 3; ++ch) EXPECT_EQ(again.values[i][ch], cpu.values[i][ch]);
  EXPECT_EQ(back->storage().total_bytes(), ct->storage().total_bytes());
  ClContext* ctx = default_context();
  if (ctx == nullptr) GTEST_SKIP() << "no OpenCL device";
  const auto dev = upload_compressed(*ct, *ctx);
  ASSERT_NE(dev, nullptr);
  LocalRadiance gpu;
  dev->relight(light, gpu);
  double se = 0, n2 = 0;
  for (std::size_t i = 0; i < cpu.values.size(); ++i)
    for (int ch = 0; ch < 3; ++ch) {
      se += std::pow(gpu.values[i][ch] - cpu.values[i][ch], 2);
      n2 += std::pow(cpu.values[i][ch], 2);
    }
  EXPECT_LT(std::sqrt(se / n2), 1e-6);
}

// ---- the BRDF-weighted signal ------------------------------------------------------------------

// 24 vertices, M = 9 (S = 3), N = 96: room for K = 4 BRDF terms below M.
TransferMatrix brdf_test_transfer() {
  return random_transfer(7, RandomTransferSpec{24, 3, 4, 4, 0.3, {3}});
}

// Phi Psi T_x for every vertex, stacked like T: the outgoing radiance towards the view cells of
// the K-term signal, the reference of the brdf signal.
Eigen::MatrixXd folded_reference(const TransferMatrix& t, const BrdfFold& fold) {
  const int m = t.local_count();
  Eigen::MatrixXd out(static_cast<Eigen::Index>(t.rows()), static_cast<Eigen::Index>(t.cols()));
  for (std::size_t x = 0; x < t.vertex_count(); ++x)
    out.middleRows(static_cast<Eigen::Index>(x) * m, m) = fold.view * folded_vertex(t, fold, x);
  return out;
}

TEST(SrbfCta, BrdfSignalStoredErrorsMatchADenseRecomputation) {
  const TransferMatrix t = brdf_test_transfer();
  const BrdfFold fold = fold_brdf(HemisphereGrid(3), CookTorrance{}, 4);
  const Eigen::MatrixXd ref = folded_reference(t, fold);
  for (const char* precision : {"float32", "float16"}) {
    const auto ct = compress(t, {{"signal", "brdf"},
                                 {"brdf_terms", "4"},
                                 {"clusters", "3"},
                                 {"rank_view", "2"},
                                 {"rank_light", "6"},
                                 {"rank_vertex", "3"},
                                 {"precision", precision}});
    const SrbfCtaArrays& a = arrays(*ct);
    EXPECT_EQ(a.signal, Signal::kBrdf);
    EXPECT_EQ(a.brdf_terms, 4);
    // Phi is orthonormal under one weight on the equal-area cells, so the error over the view
    // cells is the error in the K terms the backend measures.
    const double direct = (reconstructed(a) - ref).norm() / ref.norm();
    // float16 stores Phi U rounded, the backend measures with U rounded: close, not equal.
    EXPECT_NEAR(a.frobenius_error, direct, std::string(precision) == "float32" ? 1e-5 : 1e-4)
        << precision;
    EXPECT_GT(a.frobenius_error, a.srbf_frobenius_error) << "CTA at low rank loses nothing?";
  }
}

TEST(SrbfCta, BrdfSignalAtFullRankIsTheProjectionOfTheFoldedRows) {
  const TransferMatrix t = brdf_test_transfer();
  const auto ct = compress(t, {{"signal", "brdf"},
                               {"brdf_terms", "4"},
                               {"clusters", "1"},
                               {"rank_light", "42"},
                               {"rank_vertex", "24"},
                               {"precision", "float32"}});
  const SrbfCtaArrays& a = arrays(*ct);
  EXPECT_NEAR(a.frobenius_error, a.srbf_frobenius_error, 1e-5);
  // Independently: every folded row Psi T_x by regularised least squares.
  const BrdfFold fold = fold_brdf(HemisphereGrid(3), CookTorrance{}, 4);
  const SrbfProjector p(transfer_basis(42, a.bandwidth), CubemapLayout(4), a.ridge);
  const Eigen::MatrixXd g = pixel_values(a);
  double se = 0, n2 = 0;
  for (std::size_t x = 0; x < t.vertex_count(); ++x) {
    const Eigen::MatrixXd f = folded_vertex(t, fold, x);
    for (Eigen::Index k = 0; k < f.rows(); ++k) {
      std::vector<std::uint32_t> cols;
      std::vector<double> vals;
      for (Eigen::Index q = 0; q < f.cols(); ++q)
        if (f(k, q) != 0) cols.push_back(static_cast<std::uint32_t>(q)), vals.push_back(f(k, q));
      const Eigen::VectorXd c = p.project_sparse(cols, vals);
      se += (g * c - f.row(k).transpose()).squaredNorm();
      n2 += f.row(k).squaredNorm();
    }
  }
  EXPECT_NEAR(a.srbf_frobenius_error, std::sqrt(se / n2), 1e-6);
  // Saved and loaded, the model keeps its signal.
  const prt::testing::TempDir dir;
  save_compressed(*ct, dir.path() / "brdf.prt");
  const auto back = load_compressed(dir.path() / "brdf.prt");
  EXPECT_EQ(arrays(*back).signal, Signal::kBrdf);
  EXPECT_EQ(arrays(*back).brdf_terms, 4);
  EXPECT_THROW(compress(t, {{"signal", "brdf"}, {"brdf_terms", "10"}}), ParameterError);
}

}  // namespace
}  // namespace prt::srbf_cta
