#include "srbf_cta/clustered_tensor.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <chrono>
#include <mutex>
#include <numeric>
#include <random>

#include "prtlab/base/deterministic_reduce.h"
#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/distributed/communicator.h"
#include "prtlab/numeric/elbg.h"
#include "prtlab/numeric/row_set.h"
#include "prtlab/numeric/symmetric_eigen.h"
#include "prtlab/numeric/truncated_pca.h"
#include "prtlab/storage/content_hash.h"
#include "srbf_cta/cluster_fit_exchange.h"
#include "srbf_cta/cluster_unfolding.h"

namespace prt::srbf_cta {
namespace {

using MatF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using MapF = Eigen::Map<const MatF>;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

struct RightSingular {
  Eigen::MatrixXd v;  ///< cols x k, orthonormal
  Eigen::VectorXd sigma;
};

/// The top k right singular vectors of `a` from the Gram matrix of its smaller side: the shared
/// truncated PCA (Gram path, uncentred) when the rows are fewer, else the eigenvectors of A^T A.
/// Either way the k columns are orthonormal, completed beyond the rank of `a`.
RightSingular top_right_singular(const RowMajorMatrixXd& a, Eigen::Index k) {
  if (a.rows() <= a.cols()) {
    TruncatedPcaOptions o;
    o.components = static_cast<int>(k);
    o.method = PcaMethod::kGram;
    o.center = false;
    TruncatedPca p = truncated_pca(RowSet::dense(a), o);
    return {std::move(p.components), std::move(p.singular_values)};
  }
  // A^T A's lower triangle (all the solver reads), then its top k eigenpairs.
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(a.cols(), a.cols());
  g.selfadjointView<Eigen::Lower>().rankUpdate(a.transpose());
  SymmetricEigen e = top_symmetric_eigen(g, k);
  return {std::move(e.vectors), e.values.cwiseMax(0.0).cwiseSqrt()};
}

/// out = a * b over fixed row blocks of `a`, in parallel: the same on any thread count.
template <class A, class B>
Eigen::Matrix<typename A::Scalar, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rows_product(
    const A& a, const B& b) {
  Eigen::Matrix<typename A::Scalar, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> out(a.rows(),
                                                                                         b.cols());
  constexpr Eigen::Index kBlock = 64;
  const Eigen::Index blocks = (a.rows() + kBlock - 1) / kBlock;
  tbb::parallel_for(
      tbb::blocked_range<Eigen::Index>(0, blocks, 1),
      [&](const auto& r) {
        for (Eigen::Index blk = r.begin(); blk != r.end(); ++blk) {
          const Eigen::Index r0 = blk * kBlock, n = std::min(kBlock, a.rows() - r0);
          out.middleRows(r0, n).noalias() = a.middleRows(r0, n) * b;
        }
      },
      tbb::simple_partitioner());
  return out;
}

class Cta {
 public:
  Cta(const TensorView& t, const CtaOptions& o) : t_(t), o_(o) {
    m_.view = t.view;
    m_.light = t.light;
    const auto i1 = static_cast<int>(t.view), i2 = static_cast<int>(t.light);
    r1_ = o.rank_view == 0 ? i1 : std::min(o.rank_view, i1);
    r2_ = std::min(o.rank_light, i2);
    r3_ = std::min(o.rank_vertex, r1_ * r2_);
    m_.rank_view = r1_;
    m_.rank_light = r2_;
    m_.rank_vertex = r3_;
    norms_.resize(t.vertices);
    tbb::parallel_for(std::size_t{0}, t.vertices, [&](std::size_t x) {
      norms_[x] = MapF(t.vertex(x), i1, i2).cast<double>().squaredNorm();
    });
    m_.total_squared_norm = std::accumulate(norms_.begin(), norms_.end(), 0.0);
    m_.weights = RowMajorMatrixXd::Zero(static_cast<Eigen::Index>(t.vertices), r3_);
  }

  CtaModel run() {
    auto t0 = Clock::now();
    bool converged = false;
    if (o_.resume != nullptr) {
      resume(*o_.resume);
      converged = o_.resume->clustering_converged;
    } else {
      initialise();
      m_.times.initialisation = seconds_since(t0);
      checkpoint(false);
    }
    t0 = Clock::now();
    const double clustering_before = m_.times.clustering;
    if (!converged) clustering();
    m_.times.clustering = clustering_before + seconds_since(t0);
    t0 = Clock::now();
    approximation();
    m_.times.approximation = seconds_since(t0);
    m_.squared_error = total_error();
    return std::move(m_);
  }

 private:
  std::size_t zsize() const { return static_cast<std::size_t>(r1_) * t_.light; }
  const float* z(std::size_t x) const { return z_.data() + x * zsize(); }
  RowMajorMatrixXd zd(std::size_t x) const {
    return MapF(z(x), r1_, static_cast<Eigen::Index>(t_.light)).cast<double>();
  }

  double total_error() const {
    double e = 0;
    for (const CtaCluster& c : m_.clusters) e += c.squared_error;
    return e;
  }

  void view_basis(const Eigen::MatrixXd& gram) {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(gram);
    if (eig.info() != Eigen::Success)
      throw Error("srbf_cta: the eigen-decomposition of the view Gram matrix did not converge");
    const Eigen::Index n = gram.rows();
    m_.view_basis.resize(n, r1_);
    for (int j = 0; j < r1_; ++j) m_.view_basis.col(j) = eig.eigenvectors().col(n - 1 - j);
  }

  void project_view() {
    const MatF ut = m_.view_basis.transpose().cast<float>();
    const auto i1 = static_cast<Eigen::Index>(t_.view), i2 = static_cast<Eigen::Index>(t_.light);
    z_.resize(t_.vertices * zsize());
    products_first_.clear();  // reclassify()'s kept products were of the previous Z
    tbb::parallel_for(std::size_t{0}, t_.vertices, [&](std::size_t x) {
      Eigen::Map<MatF>(z_.data() + x * zsize(), r1_, i2).noalias() =
          ut * MapF(t_.vertex(x), i1, i2);
    });
  }

  void initialise() {
    t0_ = Clock::now();
    const auto i1 = static_cast<Eigen::Index>(t_.view), i2 = static_cast<Eigen::Index>(t_.light);
    view_basis(deterministic_reduce(
        t_.vertices, 16, Eigen::MatrixXd::Zero(i1, i1).eval(),
        [&](std::size_t begin, std::size_t end) {
          Eigen::MatrixXd g = Eigen::MatrixXd::Zero(i1, i1);
          for (std::size_t x = begin; x != end; ++x) {
            const MapF xm(t_.vertex(x), i1, i2);
            g += (xm * xm.transpose()).cast<double>();
          }
          return g;
        },
        [](Eigen::MatrixXd acc, const Eigen::MatrixXd& g) { return (acc + g).eval(); }));
    project_view();
    log_debug("srbf_cta: view basis and Z in {:.2f} s", seconds_since(t0_));
    ElbgOptions e;
    e.clusters = static_cast<int>(std::min<std::size_t>(o_.clusters, t_.vertices));
    e.seed = o_.seed;
    e.rounds = o_.elbg_rounds;
    const std::vector<float> points = elbg_points();
    const ElbgResult q = elbg(points, t_.vertices, points.size() / t_.vertices, e);
    log_debug("srbf_cta: ELBG ({} rounds, {} of {} shifts kept) at {:.2f} s", q.rounds,
              q.shifts_accepted, q.shifts_tried, seconds_since(t0_));
    m_.elbg_squared_error = q.squared_error;
    m_.assignments = q.assignments;
    m_.clusters.assign(static_cast<std::size_t>(e.clusters), {});
    vertex_bases_.assign(m_.clusters.size(), {});
    rebuild_members();
    std::vector<char> all(m_.clusters.size(), 1);
    refit(all, false);
  }

  /// The unfolded Z_x ELBG quantises: in full when they have at most `elbg_dims` values, else
  /// their coordinates in the top elbg_dims principal directions of the Z_x (uncentred; the
  /// randomised range finder of Halko et al. 2011 with one power step), where distances are
  /// those of the full vectors less the part in the discarded, least energetic directions.
  std::vector<float> elbg_points() const {
    const auto v = static_cast<Eigen::Index>(t_.vertices), d = static_cast<Eigen::Index>(zsize());
    const Eigen::Index k = std::min<Eigen::Index>({o_.elbg_dims, v, d});
    if (o_.elbg_dims == 0 || k >= d) return z_;
    const Eigen::Map<const MatF> zm(z_.data(), v, d);
    std::mt19937_64 rng(o_.seed ^ 0x5bd1e995u);
    std::normal_distribution<float> normal;
    MatF omega(d, k);
    for (Eigen::Index i = 0; i < omega.size(); ++i) omega.data()[i] = normal(rng);
    auto orth = [](const MatF& y) -> MatF {
      const Eigen::HouseholderQR<Eigen::MatrixXd> qr(y.cast<double>());
      return (qr.householderQ() * Eigen::MatrixXd::Identity(y.rows(), y.cols())).cast<float>();
    };
    // Z^T q over fixed blocks of Z's columns (each one product over all vertices), so that it
    // is the same on any thread count.
    const auto zt_times = [&](const MatF& q) -> MatF {
      MatF out(d, q.cols());
      constexpr Eigen::Index kBlock = 1024;
      const Eigen::Index blocks = (d + kBlock - 1) / kBlock;
      tbb::parallel_for(
          tbb::blocked_range<Eigen::Index>(0, blocks, 1),
          [&](const auto& r) {
            for (Eigen::Index blk = r.begin(); blk != r.end(); ++blk) {
              const Eigen::Index c0 = blk * kBlock, n = std::min(kBlock, d - c0);
              out.middleRows(c0, n).noalias() = zm.middleCols(c0, n).transpose() * q;
            }
          },
          tbb::simple_partitioner());
      return out;
    };
    MatF q = orth(rows_product(zm, omega));
    q = orth(rows_product(zm, zt_times(q)));
    const MatF b = zt_times(q).transpose();  // k x d
    const Eigen::MatrixXd g = (b * b.transpose()).cast<double>();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(g);
    // Coordinates Z V_k = Q U S: the principal axes' order does not matter to distances.
    Eigen::MatrixXd us = eig.eigenvectors();
    for (Eigen::Index j = 0; j < k; ++j)
      us.col(j) *= std::sqrt(std::max(0.0, eig.eigenvalues()[j]));
    const MatF coords = q * us.cast<float>();
    return std::vector<float>(coords.data(), coords.data() + coords.size());
  }

  void rebuild_members() {
    for (CtaCluster& c : m_.clusters) c.members.clear();
    for (std::size_t x = 0; x < t_.vertices; ++x)
      m_.clusters[m_.assignments[x]].members.push_back(static_cast<std::uint32_t>(x));
  }

  /// Refits the clusters marked in `which`. After a reclassification (`from_reclassification`)
  /// a warm cluster starts from its members' weights W_x under the bases that classified them
  /// (reclassify() keeps them): HOOI's light step first, with the orthonormalised W as the vertex
  /// basis, then the vertex step. Its error then never exceeds the reclassification's, with one
  /// vertex step where starting from the old dual basis takes two. A reseeded cluster refits
  /// from scratch, as its trial fit did.
  void refit(const std::vector<char>& which, bool warm, bool from_reclassification = false) {
    const auto t0 = Clock::now();
    step_stats_.reset();
    const auto fit = [&](std::size_t c) {
      const bool reseeded = from_reclassification && reseeded_[c];
      fit_cluster(m_.clusters[c], vertex_bases_[c], warm && !reseeded, true,
                  from_reclassification && !reseeded ? &moved_weights_ : nullptr);
    };
    if (Communicator* comm = collective(); comm != nullptr && comm->distributed()) {
      std::vector<std::size_t> todo;
      for (std::size_t c = 0; c < m_.clusters.size(); ++c)
        if (which[c]) todo.push_back(c);
      fit_clusters_on_ranks(
          *comm, todo, [&](std::size_t c) { return m_.clusters[c].members.size(); }, fit,
          [&](std::size_t c) {
            return ClusterFitState{&m_.clusters[c], &vertex_bases_[c], &m_.weights};
          });
    } else {
      tbb::parallel_for(std::size_t{0}, m_.clusters.size(), [&](std::size_t c) {
        if (which[c]) fit(c);
      });
    }
    m_.refit_errors.push_back(total_error());
    std::vector<std::size_t> sizes;
    for (std::size_t c = 0; c < m_.clusters.size(); ++c)
      if (which[c]) sizes.push_back(m_.clusters[c].members.size());
    std::sort(sizes.begin(), sizes.end());
    if (!sizes.empty())
      log_debug(
          "srbf_cta: refit of {} clusters (members min {}, median {}, max {}) in {:.2f} s: {} "
          "vertex steps ({} with Y formed, {} subspace iterations, {:.2f} s summed), {} light "
          "steps ({:.2f} s summed)",
          sizes.size(), sizes.front(), sizes[sizes.size() / 2], sizes.back(), seconds_since(t0),
          step_stats_.vertex_steps, step_stats_.formed, step_stats_.iterations,
          step_stats_.vertex_seconds, step_stats_.light_steps, step_stats_.light_seconds);
  }

  /// Modes 2 and 3 of the cluster's sub-tensor of Z with its members fixed (HOOI); the vertex
  /// basis U_v (members x r) goes to `uv`, W_x to the model when `store_weights`.
  void fit_cluster(CtaCluster& c, Eigen::MatrixXd& uv, bool warm, bool store_weights,
                   const RowMajorMatrixXd* start_weights = nullptr) {
    const auto m = static_cast<Eigen::Index>(c.members.size());
    const auto i2 = static_cast<Eigen::Index>(t_.light);
    if (m == 0) {
      c.dual.resize(0, static_cast<Eigen::Index>(r1_) * r2_);
      if (c.light.size() == 0) c.light = Eigen::MatrixXd::Identity(i2, r2_);
      uv.resize(0, 0);
      c.squared_error = 0;
      return;
    }
    if (!warm || c.light.rows() != i2) {
      // HOSVD start: the mode-2 Gram of the members' Z_x, summed in float (a start only) over
      // fixed member blocks, in order.
      const Eigen::MatrixXf g = deterministic_reduce(
          c.members.size(), 64, Eigen::MatrixXf(Eigen::MatrixXf::Zero(i2, i2)),
          [&](std::size_t begin, std::size_t end) {
            Eigen::MatrixXf b = Eigen::MatrixXf::Zero(i2, i2);
            for (std::size_t k = begin; k < end; ++k)
              b.selfadjointView<Eigen::Lower>().rankUpdate(
                  MapF(z(c.members[k]), r1_, i2).transpose());
            return b;
          },
          [](Eigen::MatrixXf acc, const Eigen::MatrixXf& b) {
            acc += b;
            return acc;
          });
      c.dual.resize(0, 0);  // its coordinates were those of the light basis replaced here
      const Eigen::MatrixXd gd = g.selfadjointView<Eigen::Lower>().toDenseMatrix().cast<double>();
      c.light = top_symmetric_eigen(gd, r2_).vectors;
    }
    int sweeps = o_.hooi_sweeps;
    const Eigen::Index r = c.dual.rows();
    if (warm && start_weights != nullptr && o_.hooi_sweeps >= 1 && r > 0 && c.light.rows() == i2) {
      Eigen::MatrixXd w(m, r);
      for (Eigen::Index k = 0; k < m; ++k) w.row(k) = start_weights->row(c.members[k]).head(r);
      const Eigen::HouseholderQR<Eigen::MatrixXd> qr(w);
      uv = qr.householderQ() * Eigen::MatrixXd::Identity(m, std::min(m, r));
      light_step(c, uv);
      vertex_step(c, uv, store_weights, true);
      --sweeps;
    } else {
      vertex_step(c, uv, store_weights, false);
    }
    for (int s = 0; s < sweeps; ++s) {
      light_step(c, uv);
      vertex_step(c, uv, store_weights, true);
    }
  }

  /// The dual vertex basis from the top right singular vectors of the cluster's unfolding
  /// (cluster_unfolding.h), started from the cluster's previous basis: `uv` (its members'
  /// coordinates) when `from_left`, else its dual basis, both valid for the current light basis.
  void vertex_step(CtaCluster& c, Eigen::MatrixXd& uv, bool store_weights, bool from_left) {
    const auto t0 = Clock::now();
    const auto m = static_cast<Eigen::Index>(c.members.size());
    const Eigen::Index w = static_cast<Eigen::Index>(r1_) * r2_;
    const Eigen::Index want = std::min<Eigen::Index>(r3_, m);
    VertexModeOptions vo;
    vo.rank = want;
    vo.seed = o_.seed + 0x9e3779b97f4a7c15ull * (c.members.empty() ? 0 : c.members[0] + 1);
    const bool have_right = c.dual.cols() == w && c.dual.rows() > 0;
    const bool have_left = from_left && uv.rows() == m && uv.cols() > 0;
    const int expected_products = have_right || have_left ? 8 : 16;
    const ClusterUnfolding y(z_.data(), r1_, static_cast<Eigen::Index>(t_.light), c.members,
                             c.light, std::min<Eigen::Index>(want + vo.oversampling, w),
                             expected_products);
    const Eigen::MatrixXd start_right =
        have_right ? Eigen::MatrixXd(c.dual.transpose()) : Eigen::MatrixXd();
    VertexMode s = top_vertex_mode(y, vo, have_right && !have_left ? &start_right : nullptr,
                                   have_left ? &uv : nullptr);
    Eigen::MatrixXd& v = s.v;
    const Eigen::VectorXd& sigma = s.sigma;
    step_stats_.add_vertex(seconds_since(t0), s.iterations, y.formed());
    // Eq. 16 inverts the core's row Gram: only directions with a singular value survive it.
    const double floor = (sigma.size() > 0 ? sigma[0] : 0.0) * 1e-9;
    Eigen::Index r = 0;
    while (r < want && sigma[r] > floor) ++r;
    v.conservativeResize(w, r);
    c.dual = v.transpose();
    // W_x = Y v in double from the stored basis: the error below is that of the model as saved.
    const Eigen::MatrixXd weights = s.weights.leftCols(r);  // m x r: W_x, rows
    uv = weights;
    for (Eigen::Index j = 0; j < r; ++j) uv.col(j) /= sigma[j];
    double err = 0;
    for (Eigen::Index k = 0; k < m; ++k) {
      err += norms_[c.members[k]] - weights.row(k).squaredNorm();
      if (store_weights) {
        auto row = m_.weights.row(c.members[k]);
        row.setZero();
        row.head(r) = weights.row(k);
      }
    }
    c.squared_error = std::max(0.0, err);
  }

  void light_step(CtaCluster& c, const Eigen::MatrixXd& uv) {
    const auto i2 = static_cast<Eigen::Index>(t_.light);
    const Eigen::Index r = uv.cols();
    if (r == 0) return;
    const auto t0 = Clock::now();
    // Mode 2 of Z_c x_3 U_v^T: rows (j, a) of Q_j = sum_x U_v(x, j) Z_x; column j of `g` is
    // Q_j flattened (row-major R1 x I2), summed over fixed blocks (any thread count, same sum).
    const Eigen::MatrixXd g =
        members_transpose_product(z_.data(), static_cast<Eigen::Index>(zsize()), c.members, uv);
    RowMajorMatrixXd q(r, static_cast<Eigen::Index>(zsize()));
    for (Eigen::Index j = 0; j < r; ++j) q.row(j) = g.col(j).transpose();
    const Eigen::Map<const RowMajorMatrixXd> a(q.data(), r * r1_, i2);
    c.light = top_right_singular(a, r2_).v;
    step_stats_.add_light(seconds_since(t0));
  }

  /// Digest of the bases a cluster's columns of `products_` were computed with.
  static Hash128 bases_digest(const CtaCluster& c) {
    Hasher h;
    h.add(static_cast<std::uint64_t>(c.dual.rows())).add(static_cast<std::uint64_t>(c.dual.cols()));
    h.add_array(std::span<const double>(c.dual.data(), static_cast<std::size_t>(c.dual.size())));
    h.add(static_cast<std::uint64_t>(c.light.rows()))
        .add(static_cast<std::uint64_t>(c.light.cols()));
    h.add_array(std::span<const double>(c.light.data(), static_cast<std::size_t>(c.light.size())));
    return h.digest();
  }

  /// Returns the vertices moved and the total error they shed (in double, with these bases).
  std::pair<std::size_t, double> reclassify() {
    const auto t0 = Clock::now();
    const Eigen::Index zs = static_cast<Eigen::Index>(zsize());
    std::vector<Eigen::Index> first{0};
    for (const CtaCluster& c : m_.clusters) first.push_back(first.back() + c.dual.rows());
    // W_xc for every vertex and cluster is kept between passes: only the clusters whose bases
    // changed since (those refit or reseeded) are multiplied again, a fraction of the clusters
    // once the clustering settles.
    if (first != products_first_) {
      products_.resize(static_cast<Eigen::Index>(t_.vertices), first.back());
      products_first_ = first;
      products_bases_.assign(m_.clusters.size(), Hash128{});
    }
    std::vector<std::size_t> stale;
    std::vector<Hash128> digests(m_.clusters.size());
    tbb::parallel_for(std::size_t{0}, m_.clusters.size(),
                      [&](std::size_t c) { digests[c] = bases_digest(m_.clusters[c]); });
    for (std::size_t c = 0; c < m_.clusters.size(); ++c)
      if (digests[c] != products_bases_[c] && first[c + 1] > first[c]) stale.push_back(c);
    // B's rows refold(V_cj) U_c^T (R1 x I2) for the stale clusters, so that W_xc = B_c vec(Z_x).
    std::vector<Eigen::Index> row_of{0};
    for (const std::size_t c : stale) row_of.push_back(row_of.back() + first[c + 1] - first[c]);
    // In float: the products only choose candidates, each move is decided in double below.
    MatF b(row_of.back(), zs);
    tbb::parallel_for(std::size_t{0}, stale.size(), [&](std::size_t k) {
      const CtaCluster& cl = m_.clusters[stale[k]];
      const MatF dual = cl.dual.cast<float>();
      const MatF light_t = cl.light.transpose().cast<float>();
      for (Eigen::Index j = 0; j < cl.dual.rows(); ++j)
        Eigen::Map<MatF>(b.row(row_of[k] + j).data(), r1_, static_cast<Eigen::Index>(t_.light))
            .noalias() = MapF(dual.row(j).data(), r1_, r2_) * light_t;
    });
    const Eigen::Map<const MatF> zall(z_.data(), static_cast<Eigen::Index>(t_.vertices), zs);
    std::vector<std::uint32_t> next = m_.assignments;
    moved_weights_.resize(static_cast<Eigen::Index>(t_.vertices), r3_);
    reseeded_.assign(m_.clusters.size(), 0);
    std::vector<double> gain(t_.vertices, 0.0);
    constexpr Eigen::Index kBlock = 256;
    tbb::parallel_for(
        tbb::blocked_range<Eigen::Index>(0, static_cast<Eigen::Index>(t_.vertices), kBlock),
        [&](const auto& r) {
          const Eigen::Index rows = r.end() - r.begin();
          if (b.rows() > 0) {
            const MatF w = zall.middleRows(r.begin(), rows) * b.transpose();
            for (std::size_t k = 0; k < stale.size(); ++k)
              products_.block(r.begin(), first[stale[k]], rows, row_of[k + 1] - row_of[k]) =
                  w.middleCols(row_of[k], row_of[k + 1] - row_of[k]);
          }
          for (Eigen::Index x = r.begin(); x < r.end(); ++x) {
            const auto row = products_.row(x);
            const auto xs = static_cast<std::size_t>(x);
            const std::uint32_t cur = m_.assignments[xs];
            std::uint32_t best = cur;
            double best_kept = -1;
            for (std::size_t c = 0; c < m_.clusters.size(); ++c) {
              const double kept = row.segment(first[c], first[c + 1] - first[c])
                                      .template cast<double>()
                                      .squaredNorm();
              if (kept > best_kept) best_kept = kept, best = static_cast<std::uint32_t>(c);
            }
            if (best != cur) {
              // The float products choose the candidate; the move is decided in double.
              const double e_cur = error_in(xs, cur), e_new = error_in(xs, best);
              if (e_new < e_cur) {
                next[xs] = best;
                gain[xs] = e_cur - e_new;
              }
            }
            // W_x in the cluster it ends in, with the bases that classified: the refit's start.
            const std::uint32_t fin = next[xs];
            const Eigen::Index len = first[fin + 1] - first[fin];
            auto dst = moved_weights_.row(x);
            dst.setZero();
            dst.head(len) = row.segment(first[fin], len).template cast<double>();
          }
        },
        tbb::simple_partitioner());  // fixed blocks: the same products on any thread count
    for (const std::size_t c : stale) products_bases_[c] = digests[c];
    log_debug(
        "srbf_cta: reclassification with the products of {} of {} clusters recomputed in "
        "{:.2f} s",
        stale.size(), m_.clusters.size(), seconds_since(t0));
    std::size_t moved = 0;
    for (std::size_t x = 0; x < t_.vertices; ++x) moved += next[x] != m_.assignments[x];
    m_.assignments = std::move(next);
    rebuild_members();
    const double shed = std::accumulate(gain.begin(), gain.end(), 0.0) + reseed_empty();
    return {moved, shed};
  }

  double error_in(std::size_t x, std::size_t c) const {
    const CtaCluster& cl = m_.clusters[c];
    const RowMajorMatrixXd p = zd(x) * cl.light;
    const Eigen::Map<const Eigen::VectorXd> y(p.data(), p.size());
    return norms_[x] - (cl.dual * y).squaredNorm();
  }

  /// An emptied cluster takes the vertex it approximates best on its own, when that lowers the
  /// vertex's error (candidates: the worst-approximated vertices of clusters with others left).
  double reseed_empty() {
    double shed = 0;
    for (std::size_t c = 0; c < m_.clusters.size(); ++c) {
      if (!m_.clusters[c].members.empty()) continue;
      std::vector<std::pair<double, std::uint32_t>> worst;
      for (std::size_t x = 0; x < t_.vertices; ++x)
        if (m_.clusters[m_.assignments[x]].members.size() > 1)
          worst.emplace_back(error_in(x, m_.assignments[x]), static_cast<std::uint32_t>(x));
      const std::size_t take = std::min<std::size_t>(8, worst.size());
      std::partial_sort(worst.begin(), worst.begin() + static_cast<std::ptrdiff_t>(take),
                        worst.end(), std::greater<>());
      for (std::size_t k = 0; k < take; ++k) {
        CtaCluster trial;
        trial.members = {worst[k].second};
        Eigen::MatrixXd uv;
        fit_cluster(trial, uv, false, false);
        if (trial.squared_error < worst[k].first) {
          shed += worst[k].first - trial.squared_error;
          m_.assignments[worst[k].second] = static_cast<std::uint32_t>(c);
          m_.clusters[c].light = trial.light;
          reseeded_[c] = 1;
          break;
        }
      }
      rebuild_members();
    }
    return shed;
  }

  void checkpoint(bool converged) {
    if (!o_.on_checkpoint) return;
    CtaCheckpoint c{m_, vertex_bases_, converged};
    o_.on_checkpoint(c);
  }

  void resume(const CtaCheckpoint& c) {
    const CtaModel& r = c.model;
    if (r.view != t_.view || r.light != t_.light || r.assignments.size() != t_.vertices ||
        r.rank_view != r1_ || r.rank_light != r2_ || r.rank_vertex != r3_ ||
        c.vertex_bases.size() != r.clusters.size())
      throw ParameterError(
          "srbf_cta: the checkpoint to resume from is of another tensor or other ranks");
    m_ = r;
    vertex_bases_ = c.vertex_bases;
    project_view();
    log_debug("srbf_cta: resumed after {} clustering iterations (squared error {:.6g})",
              m_.clustering_iterations, total_error());
  }

  void clustering() {
    for (int it = m_.clustering_iterations; it < o_.clustering_iterations; ++it) {
      const double before = total_error();
      const std::vector<std::uint32_t> old = m_.assignments;
      const auto [moved, shed] = reclassify();
      // The total with the bases that classified, at the new membership.
      m_.reclassification_errors.push_back(before);
      m_.reclassification_errors.push_back(before - shed);
      m_.clustering_iterations = it + 1;
      if (moved == 0) {
        report("clustering", it, before, 0);
        checkpoint(true);
        break;
      }
      std::vector<char> changed(m_.clusters.size(), 0);
      for (std::size_t x = 0; x < t_.vertices; ++x)
        if (old[x] != m_.assignments[x]) changed[old[x]] = changed[m_.assignments[x]] = 1;
      for (std::size_t c = 0; c < m_.clusters.size(); ++c)
        if (m_.clusters[c].members.empty()) changed[c] = 1;
      refit(changed, true, true);
      const double now = total_error();
      report("clustering", it, now, moved);
      // Converged when a whole iteration sheds less than the tolerance's share of the error.
      if (before > 0 && before - now <= o_.clustering_tolerance * before) {
        checkpoint(true);
        break;
      }
      if (it + 1 < o_.clustering_iterations) checkpoint(false);
    }
  }

  void approximation() {
    if (r1_ == static_cast<int>(t_.view)) return;  // U is a rotation: nothing to improve
    const auto i1 = static_cast<Eigen::Index>(t_.view), i2 = static_cast<Eigen::Index>(t_.light);
    double previous = total_error();
    for (int it = 0; it < o_.approximation_iterations; ++it) {
      // Mode 1 of every cluster's X_c x_2 U_c^T x_3 U_v,c^T.
      const auto cluster_gram = [&](std::size_t c) -> Eigen::MatrixXd {
        Eigen::MatrixXd g = Eigen::MatrixXd::Zero(i1, i1);
        const CtaCluster& cl = m_.clusters[c];
        const Eigen::MatrixXd& uv = vertex_bases_[c];
        if (cl.members.empty() || uv.cols() == 0) return g;
        std::vector<RowMajorMatrixXd> q(static_cast<std::size_t>(uv.cols()),
                                        RowMajorMatrixXd::Zero(i1, r2_));
        for (std::size_t k = 0; k < cl.members.size(); ++k) {
          const RowMajorMatrixXd p =
              MapF(t_.vertex(cl.members[k]), i1, i2).cast<double>() * cl.light;
          for (Eigen::Index j = 0; j < uv.cols(); ++j)
            q[static_cast<std::size_t>(j)] += uv(static_cast<Eigen::Index>(k), j) * p;
        }
        for (const RowMajorMatrixXd& qj : q) g += qj * qj.transpose();
        return g;
      };
      view_basis(deterministic_reduce(
          m_.clusters.size(), 1, Eigen::MatrixXd::Zero(i1, i1).eval(),
          [&](std::size_t c, std::size_t) { return cluster_gram(c); },
          [](Eigen::MatrixXd acc, const Eigen::MatrixXd& g) { return (acc + g).eval(); }));
      project_view();
      std::vector<char> all(m_.clusters.size(), 1);
      refit(all, true);
      const double now = total_error();
      m_.approximation_iterations = it + 1;
      report("approximation", it, now, 0);
      if (!(previous > 0) || previous - now <= o_.tolerance * previous) break;
      previous = now;
    }
  }

  void report(const char* phase, int it, double err, std::size_t moved) const {
    if (o_.on_pass) o_.on_pass(CtaPass{phase, it, err, moved});
  }

  /// What the refit's steps cost, summed over its clusters (which run in parallel).
  struct StepStats {
    std::mutex mutex;
    double vertex_seconds = 0, light_seconds = 0;
    int vertex_steps = 0, light_steps = 0, iterations = 0, formed = 0;
    void reset() {
      vertex_seconds = light_seconds = 0;
      vertex_steps = light_steps = iterations = formed = 0;
    }
    void add_vertex(double s, int it, bool y_formed) {
      const std::lock_guard lock(mutex);
      vertex_seconds += s;
      ++vertex_steps;
      iterations += it;
      formed += y_formed ? 1 : 0;
    }
    void add_light(double s) {
      const std::lock_guard lock(mutex);
      light_seconds += s;
      ++light_steps;
    }
  };

  const TensorView& t_;
  const CtaOptions& o_;
  StepStats step_stats_;
  RowMajorMatrixXd moved_weights_;  ///< vertices x R3: W_x in its new cluster, old bases
  MatF products_;                   ///< vertices x sum of R3: W_xc in float, reclassify()'s
  std::vector<Eigen::Index> products_first_;  ///< products_' first column of each cluster
  std::vector<Hash128> products_bases_;       ///< the bases each cluster's columns came from
  std::vector<char> reseeded_;  ///< clusters an emptied cluster's reseed gave a new start
  Clock::time_point t0_;
  int r1_ = 0, r2_ = 0, r3_ = 0;
  std::vector<double> norms_;
  std::vector<float> z_;
  std::vector<Eigen::MatrixXd> vertex_bases_;
  CtaModel m_;
};

}  // namespace

CtaModel clustered_tensor_approximation(const TensorView& t, const CtaOptions& o) {
  if (t.vertices == 0 || t.view == 0 || t.light == 0)
    throw ParameterError(
        fmt::format("srbf_cta: a tensor of {} x {} x {} has nothing to approximate", t.view,
                    t.light, t.vertices));
  if (t.values.size() != t.vertices * t.view * t.light)
    throw ParameterError(fmt::format("srbf_cta: {} values for a {} x {} x {} tensor",
                                     t.values.size(), t.view, t.light, t.vertices));
  if (o.clusters < 1 || o.rank_view < 0 || o.rank_light < 1 || o.rank_vertex < 1)
    throw ParameterError(fmt::format(
        "srbf_cta: clusters {} and ranks ({}, {}, {}) must be at least 1 (rank_view 0: all)",
        o.clusters, o.rank_view, o.rank_light, o.rank_vertex));
  if (!std::all_of(t.values.begin(), t.values.end(), [](float v) { return std::isfinite(v); }))
    throw ParameterError("srbf_cta: the tensor has a value that is not finite");
  return Cta(t, o).run();
}

RowMajorMatrixXd reconstruct_vertex(const CtaModel& m, std::size_t x) {
  const CtaCluster& c = m.clusters[m.assignments[x]];
  const Eigen::Index r = c.dual.rows();
  const Eigen::RowVectorXd y = m.weights.row(static_cast<Eigen::Index>(x)).head(r) * c.dual;
  const Eigen::Map<const RowMajorMatrixXd> k(y.data(), m.rank_view, m.rank_light);
  return m.view_basis * k * c.light.transpose();
}

double vertex_cluster_error(const TensorView& t, const CtaModel& m, std::size_t x, std::size_t c) {
  const auto i1 = static_cast<Eigen::Index>(t.view), i2 = static_cast<Eigen::Index>(t.light);
  const RowMajorMatrixXd xm = MapF(t.vertex(x), i1, i2).cast<double>();
  const CtaCluster& cl = m.clusters[c];
  const RowMajorMatrixXd p = m.view_basis.transpose() * xm * cl.light;
  const Eigen::Map<const Eigen::VectorXd> y(p.data(), p.size());
  const Eigen::RowVectorXd back = (cl.dual * y).transpose() * cl.dual;
  const Eigen::Map<const RowMajorMatrixXd> k(back.data(), m.rank_view, m.rank_light);
  return (xm - m.view_basis * k * cl.light.transpose()).squaredNorm();
}

}  // namespace prt::srbf_cta
