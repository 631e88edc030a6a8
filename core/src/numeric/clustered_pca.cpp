#include "prtlab/numeric/clustered_pca.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>

#include "numeric/row_access.h"
#include "prtlab/base/error.h"
#include "prtlab/base/named_warning.h"
#include "prtlab/numeric/kmeans.h"
#include "prtlab/numeric/row_products.h"
#include "prtlab/numeric/truncated_pca.h"

namespace prt {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The points of every cluster, cluster after cluster (a counting sort of the assignments).
struct Members {
  std::vector<std::uint32_t> order;
  std::vector<std::size_t> offsets;  // clusters + 1
  std::span<const std::uint32_t> of(std::size_t c) const {
    return std::span<const std::uint32_t>(order).subspan(offsets[c], offsets[c + 1] - offsets[c]);
  }
};

Members group(std::span<const std::uint32_t> assignments, std::size_t clusters) {
  Members m;
  m.offsets.assign(clusters + 1, 0);
  for (std::uint32_t a : assignments) ++m.offsets[a + 1];
  std::partial_sum(m.offsets.begin(), m.offsets.end(), m.offsets.begin());
  m.order.resize(assignments.size());
  std::vector<std::size_t> next(m.offsets.begin(), m.offsets.end() - 1);
  for (std::size_t p = 0; p < assignments.size(); ++p) {
    m.order[next[assignments[p]]++] = static_cast<std::uint32_t>(p);
  }
  return m;
}

Eigen::VectorXd mean_of(const RowSet& subset) {
  return numeric_detail::visit_rows(subset, [&](const auto& a) {
    Eigen::VectorXd mu = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(a.cols()));
    for (std::size_t i = 0; i < a.rows(); ++i) numeric_detail::axpy(a, i, 1.0, mu.data());
    return Eigen::VectorXd(mu / static_cast<double>(std::max<std::size_t>(1, a.rows())));
  });
}

std::uint64_t stored_entries(const RowSet& points) {
  if (const auto* csr = std::get_if<RowSet::Csr>(&points.storage())) {
    if (!points.has_selection()) return csr->offsets.back();
    std::uint64_t n = 0;
    for (std::size_t i = 0; i < points.rows(); ++i) {
      const std::size_t r = points.stored_row(i);
      n += csr->offsets[r + 1] - csr->offsets[r];
    }
    return n;
  }
  return static_cast<std::uint64_t>(points.rows()) * points.cols();
}

class Engine {
 public:
  Engine(const RowSet& points, const ClusteredPcaOptions& o)
      : points_(points), o_(o), n_(points.cols()), m_(points.rows()) {
    norms_ = row_squared_norms(points);
    nnz_ = stored_entries(points);
  }

  ClusteredPca run() {
    vq();
    if (o_.method == CpcaMethod::kStatic) {
      update(std::vector<int>(clusters_.size(), o_.components), true);
    } else {
      iterate();
      if (o_.method == CpcaMethod::kAdaptive) adapt();
    }
    return finish();
  }

 private:
  void record(const std::string& stage, int components, int iteration, std::size_t reassigned) {
    double sum = 0.0;
    for (double e : errors_) sum += e;
    CpcaPass pass{stage, components, iteration, sum, reassigned};
    out_.history.push_back(pass);
    if (o_.on_pass) o_.on_pass(pass);
  }

  void vq() {
    const auto t0 = Clock::now();
    KMeansOptions km;
    km.clusters = o_.clusters;
    km.init = KMeansInit::kLbgSplitting;
    km.seed = o_.seed;
    km.max_iterations = o_.vq_iterations;
    const KMeansResult r = kmeans(points_, km);
    assignments_ = r.assignments;
    clusters_.resize(static_cast<std::size_t>(o_.clusters));
    for (std::size_t c = 0; c < clusters_.size(); ++c) {
      clusters_[c].mean = r.centroids.row(static_cast<Eigen::Index>(c)).transpose();
      clusters_[c].components.resize(static_cast<Eigen::Index>(n_), 0);
      clusters_[c].count = r.counts[c];
    }
    out_.times.vq += seconds_since(t0);
    CpcaPass pass{"vq", 0, r.iterations, r.squared_error, 0};
    out_.history.push_back(pass);
    if (o_.on_pass) o_.on_pass(pass);
  }

  // Each cluster's mean and top k[c] components from its current members, starting from its
  // previous components.
  void update(const std::vector<int>& k, bool converge) {
    const auto t0 = Clock::now();
    const Members members = group(assignments_, clusters_.size());
    tbb::parallel_for(std::size_t{0}, clusters_.size(), [&](std::size_t c) {
      const auto rows = members.of(c);
      CpcaCluster& cl = clusters_[c];
      cl.count = rows.size();
      if (rows.empty()) return;  // reseeded by reseed_empty()
      const RowSet subset = points_.subset(rows);
      const int kc = std::min(k[c], static_cast<int>(n_));
      if (kc == 0) {
        cl.mean = mean_of(subset);
        cl.components.resize(static_cast<Eigen::Index>(n_), 0);
        cl.eigenvalues.resize(0);
        return;
      }
      TruncatedPcaOptions po;
      po.components = kc;
      po.tolerance = o_.pca_tolerance;
      const bool full = converge || o_.converge_every_update;
      po.max_iterations = full ? 100 : o_.pca_iterations_per_pass;
      if (!full) po.oversampling = o_.pca_oversampling;
      po.seed = o_.seed * 0x9E3779B97F4A7C15ull + c;
      if (cl.components.cols() > 0) po.start = cl.components;
      const TruncatedPca p = truncated_pca(subset, po);
      cl.mean = p.mean;
      cl.components = p.components;
      cl.eigenvalues = p.eigenvalues;
    });
    reseed_empty();
    out_.times.pca += seconds_since(t0);
    ++out_.times.pca_updates;
  }

  // A cluster left without points takes the worst-approximated point of a cluster that has more
  // than one, as VQ codebooks are usually repaired; its components restart from zero.
  void reseed_empty() {
    std::vector<std::size_t> empty;
    for (std::size_t c = 0; c < clusters_.size(); ++c) {
      if (clusters_[c].count == 0) empty.push_back(c);
    }
    if (empty.empty()) return;
    if (!reported_empty_) {
      // Once per fit: an empty cluster is a sign of more clusters than distinct rows, which
      // the user should know stores clusters that represent nothing new.
      reported_empty_ = true;
      log_warn_named("pca-empty-clusters",
                     "clustered PCA: {} of {} clusters lost every row (more clusters than the "
                     "{} rows support); each takes the worst-approximated row of a larger one",
                     empty.size(), clusters_.size(), m_);
    }
    std::vector<std::uint32_t> by_error(m_);
    std::iota(by_error.begin(), by_error.end(), 0u);
    const bool have_errors = errors_.size() == m_;
    std::stable_sort(by_error.begin(), by_error.end(), [&](std::uint32_t a, std::uint32_t b) {
      return have_errors ? errors_[a] > errors_[b] : norms_[a] > norms_[b];
    });
    std::size_t next = 0;
    for (std::size_t c : empty) {
      while (next < by_error.size() && clusters_[assignments_[by_error[next]]].count < 2) ++next;
      if (next == by_error.size()) break;
      const std::uint32_t p = by_error[next++];
      --clusters_[assignments_[p]].count;
      assignments_[p] = static_cast<std::uint32_t>(c);
      const std::uint32_t one[] = {p};
      clusters_[c].mean = points_.subset(one).to_dense().row(0).transpose();
      clusters_[c].components.setZero();
      clusters_[c].eigenvalues.setZero();
      clusters_[c].count = 1;
    }
  }

  // Every point to the cluster of least approximation error with the clusters' current models.
  std::size_t classify() {
    const auto t0 = Clock::now();
    const std::size_t nc = clusters_.size();
    std::vector<std::size_t> first(nc + 1, 0);
    for (std::size_t c = 0; c < nc; ++c) {
      first[c + 1] = first[c] + 1 + static_cast<std::size_t>(clusters_[c].k());
    }
    const std::size_t width = first[nc];
    RowMajorMatrixXf b(static_cast<Eigen::Index>(n_), static_cast<Eigen::Index>(width));
    std::vector<double> mean_sq(nc);
    std::vector<double> mean_dot(width, 0.0);
    for (std::size_t c = 0; c < nc; ++c) {
      const CpcaCluster& cl = clusters_[c];
      const auto f = static_cast<Eigen::Index>(first[c]);
      // The constants from the float columns the product uses, so that the error expansion is
      // exact for the (rounded) model it classifies against.
      b.col(f) = cl.mean.cast<float>();
      const Eigen::VectorXd mean_f = b.col(f).cast<double>();
      mean_sq[c] = mean_f.squaredNorm();
      for (int i = 0; i < cl.k(); ++i) {
        b.col(f + 1 + i) = cl.components.col(i).cast<float>();
        mean_dot[first[c] + 1 + static_cast<std::size_t>(i)] =
            mean_f.dot(b.col(f + 1 + i).cast<double>());
      }
    }
    std::vector<std::uint32_t> next(m_);
    errors_.resize(m_);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m_, 256), [&](const auto& r) {
      std::vector<float> y(width);
      for (std::size_t p = r.begin(); p != r.end(); ++p) {
        multiply_row(points_, p, b, y);
        const double x2 = norms_[static_cast<Eigen::Index>(p)];
        double best = std::numeric_limits<double>::infinity();
        std::uint32_t arg = 0;
        for (std::size_t c = 0; c < nc; ++c) {
          const std::size_t f = first[c];
          double e = x2 - 2.0 * y[f] + mean_sq[c];
          for (std::size_t j = f + 1; j < first[c + 1]; ++j) {
            const double d = static_cast<double>(y[j]) - mean_dot[j];
            e -= d * d;
          }
          if (e < best) {
            best = e;
            arg = static_cast<std::uint32_t>(c);
          }
        }
        next[p] = arg;
        errors_[p] = std::max(0.0, best);
      }
    });
    std::size_t moved = 0;
    for (std::size_t p = 0; p < m_; ++p) moved += next[p] != assignments_[p];
    assignments_ = std::move(next);
    out_.times.classify += seconds_since(t0);
    ++out_.times.classify_passes;
    out_.times.classify_flops += 2.0 * static_cast<double>(nnz_) * static_cast<double>(width);
    return moved;
  }

  void iterate() {
    const auto nc = clusters_.size();
    for (int j = 1; j <= o_.components; ++j) {
      for (int it = 0; it < o_.iterations_per_component; ++it) {
        update(std::vector<int>(nc, j), false);
        const std::size_t moved = classify();
        record("iterative", j, it, moved);
        if (moved == 0) break;
      }
    }
    update(std::vector<int>(nc, o_.components), true);
  }

  void adapt() {
    const auto nc = clusters_.size();
    int kmax = o_.adaptive_max_components > 0 ? o_.adaptive_max_components
                                              : std::max(1, 4 * o_.components);
    kmax = std::min<int>(kmax, static_cast<int>(n_));
    for (int it = 0; it < o_.adaptive_iterations; ++it) {
      const std::size_t moved = classify();
      update(std::vector<int>(nc, kmax), it + 1 == o_.adaptive_iterations);
      const std::vector<int> k = adaptive_allocation(clusters_, o_.components, o_.adaptive_rule,
                                                     o_.adaptive_weight_cost, n_);
      for (std::size_t c = 0; c < nc; ++c) {
        CpcaCluster& cl = clusters_[c];
        cl.components =
            cl.components.leftCols(std::min<Eigen::Index>(k[c], cl.components.cols())).eval();
        cl.eigenvalues =
            cl.eigenvalues.head(std::min<Eigen::Index>(k[c], cl.eigenvalues.size())).eval();
      }
      // The error of this pass's classification (under the previous pass's counts).
      record("adaptive", o_.components, it, moved);
    }
  }

  ClusteredPca finish() {
    const auto t0 = Clock::now();
    const std::size_t nc = clusters_.size();
    // Per cluster [mean, components] as an n x (k + 1) row-major block: one product per point
    // gives x . mean and x . u_i.
    std::vector<RowMajorMatrixXd> blocks(nc);
    std::vector<Eigen::VectorXd> mean_dot(nc);
    for (std::size_t c = 0; c < nc; ++c) {
      const CpcaCluster& cl = clusters_[c];
      blocks[c].resize(static_cast<Eigen::Index>(n_), cl.k() + 1);
      blocks[c].col(0) = cl.mean;
      blocks[c].rightCols(cl.k()) = cl.components;
      mean_dot[c] = cl.components.transpose() * cl.mean;
    }
    out_.weight_offsets.assign(m_ + 1, 0);
    for (std::size_t p = 0; p < m_; ++p) {
      out_.weight_offsets[p + 1] =
          out_.weight_offsets[p] + static_cast<std::uint64_t>(clusters_[assignments_[p]].k());
    }
    out_.weights.assign(out_.weight_offsets.back(), 0.0);
    std::vector<double> err(m_, 0.0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m_, 256), [&](const auto& r) {
      std::vector<double> y;
      for (std::size_t p = r.begin(); p != r.end(); ++p) {
        const std::uint32_t c = assignments_[p];
        const CpcaCluster& cl = clusters_[c];
        y.resize(static_cast<std::size_t>(cl.k()) + 1);
        multiply_row(points_, p, blocks[c], y);
        double e = norms_[static_cast<Eigen::Index>(p)] - 2.0 * y[0] + cl.mean.squaredNorm();
        double* w = out_.weights.data() + out_.weight_offsets[p];
        for (int i = 0; i < cl.k(); ++i) {
          w[i] = y[static_cast<std::size_t>(i) + 1] - mean_dot[c][i];
          e -= w[i] * w[i];
        }
        err[p] = std::max(0.0, e);
      }
    });
    out_.times.weights += seconds_since(t0);
    errors_ = err;
    out_.squared_error = 0.0;
    for (double e : err) out_.squared_error += e;
    out_.total_squared_norm = norms_.sum();
    int mean_k = 0;
    if (m_ > 0)
      mean_k = static_cast<int>(std::lround(static_cast<double>(out_.weights.size()) / m_));
    CpcaPass pass{"final", mean_k, 0, out_.squared_error, 0};
    out_.history.push_back(pass);
    if (o_.on_pass) o_.on_pass(pass);
    out_.assignments = std::move(assignments_);
    out_.clusters = std::move(clusters_);
    return std::move(out_);
  }

  const RowSet& points_;
  const ClusteredPcaOptions& o_;
  std::size_t n_, m_;
  std::uint64_t nnz_ = 0;
  Eigen::VectorXd norms_;
  std::vector<std::uint32_t> assignments_;
  std::vector<CpcaCluster> clusters_;
  std::vector<double> errors_;
  bool reported_empty_ = false;
  ClusteredPca out_;
};

}  // namespace

std::vector<int> adaptive_allocation(std::span<const CpcaCluster> clusters, int components,
                                     CpcaAdaptiveRule rule, double weight_cost, std::size_t dim) {
  const bool sloan = rule == CpcaAdaptiveRule::kSloan;
  // A component of cluster c costs its m_c weights and, in the storage rule, its own dim
  // values (the paper's storage model of section 4.1). The storage rule's budget is what n'
  // components per cluster store, so adaptive never stores more than iterative; the paper's
  // rule counts weights only (section 4.3 ranks by D^2 / m_c, the same ranking when dim << m_c,
  // as for its 25-D signals; for T's 6,144-D rows the representatives dominate).
  const auto n = static_cast<double>(dim);
  const auto cost_of = [&](const CpcaCluster& cl) {
    return sloan ? static_cast<double>(cl.count) : weight_cost * static_cast<double>(cl.count) + n;
  };
  double budget = 0;
  for (const CpcaCluster& cl : clusters) budget += cost_of(cl) * components;
  // Round-off must not let the uniform allocation itself miss the budget.
  budget *= 1 + 1e-12;
  struct Candidate {
    double rate;
    std::uint32_t cluster;
    int index;
  };
  std::vector<Candidate> cand;
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    const CpcaCluster& cl = clusters[c];
    if (cl.count == 0) continue;
    for (Eigen::Index i = 0; i < cl.eigenvalues.size(); ++i) {
      if (cl.eigenvalues[i] > 0.0) {
        cand.push_back(
            {cl.eigenvalues[i] / cost_of(cl), static_cast<std::uint32_t>(c), static_cast<int>(i)});
      }
    }
  }
  std::stable_sort(cand.begin(), cand.end(),
                   [](const Candidate& a, const Candidate& b) { return a.rate > b.rate; });
  std::vector<int> k(clusters.size(), 0);
  double used = 0;
  for (const Candidate& cd : cand) {
    // A cluster's components come in order: one that is not next is skipped (its rate can
    // exceed its predecessor's only through rounding of nearly equal eigenvalues).
    if (cd.index != k[cd.cluster]) continue;
    const double cost = cost_of(clusters[cd.cluster]);
    if (used + cost > budget) {
      if (sloan) break;
      continue;
    }
    ++k[cd.cluster];
    used += cost;
  }
  return k;
}

ClusteredPca clustered_pca(const RowSet& points, const ClusteredPcaOptions& o) {
  const std::size_t m = points.rows();
  if (o.clusters < 1 || static_cast<std::size_t>(o.clusters) > m) {
    throw ParameterError(
        fmt::format("clustered_pca: {} clusters asked of {} points", o.clusters, m));
  }
  if (o.components < 0 || static_cast<std::size_t>(o.components) > points.cols()) {
    throw ParameterError(fmt::format("clustered_pca: {} components asked of dimension {}",
                                     o.components, points.cols()));
  }
  if (o.vq_iterations < 0 || o.iterations_per_component < 0 || o.adaptive_iterations < 0 ||
      o.adaptive_max_components < 0 || o.pca_iterations_per_pass < 0 || o.pca_oversampling < 0) {
    throw ParameterError("clustered_pca: iteration counts must be >= 0");
  }
  if (!(o.adaptive_weight_cost > 0.0) || !std::isfinite(o.adaptive_weight_cost)) {
    throw ParameterError("clustered_pca: the adaptive weight cost must be a positive number");
  }
  if (!(o.pca_tolerance >= 0.0)) {
    throw ParameterError("clustered_pca: the PCA tolerance must be >= 0");
  }
  Engine engine(points, o);
  return engine.run();
}

double affine_codebook_squared_error(const RowSet& points,
                                     std::span<const std::uint32_t> assignments,
                                     const RowMajorMatrixXd& reps,
                                     std::span<const std::uint32_t> first,
                                     std::span<const double> weights,
                                     std::span<const std::uint64_t> weight_offsets) {
  const std::size_t m = points.rows();
  const std::size_t n = points.cols();
  if (assignments.size() != m || weight_offsets.size() != m + 1 || first.empty() ||
      static_cast<std::size_t>(reps.cols()) != n || first.back() != reps.rows() ||
      weight_offsets.back() != weights.size()) {
    throw ParameterError("affine_codebook_squared_error: the codebook does not match the points");
  }
  const std::size_t nc = first.size() - 1;
  std::vector<RowMajorMatrixXd> blocks(nc);
  std::vector<Eigen::MatrixXd> gram(nc);
  for (std::size_t c = 0; c < nc; ++c) {
    if (first[c + 1] <= first[c]) {
      throw ParameterError(fmt::format("affine_codebook_squared_error: cluster {} has no mean", c));
    }
    const auto rows = reps.middleRows(first[c], first[c + 1] - first[c]);
    blocks[c] = rows.transpose();
    gram[c] = rows * rows.transpose();
  }
  for (std::size_t p = 0; p < m; ++p) {
    const std::uint32_t c = assignments[p];
    if (c >= nc) {
      throw ParameterError(
          fmt::format("affine_codebook_squared_error: point {} is in cluster {} of {}", p, c, nc));
    }
    if (weight_offsets[p + 1] - weight_offsets[p] != first[c + 1] - first[c] - 1) {
      throw ParameterError(fmt::format(
          "affine_codebook_squared_error: point {} has {} weights, its cluster {} vectors", p,
          weight_offsets[p + 1] - weight_offsets[p], first[c + 1] - first[c] - 1));
    }
  }
  const Eigen::VectorXd norms = row_squared_norms(points);
  std::vector<double> err(m, 0.0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 256), [&](const auto& r) {
    std::vector<double> y;
    Eigen::VectorXd a;
    for (std::size_t p = r.begin(); p != r.end(); ++p) {
      const std::uint32_t c = assignments[p];
      const auto width = static_cast<std::size_t>(blocks[c].cols());
      y.resize(width);
      multiply_row(points, p, blocks[c], y);
      a.resize(static_cast<Eigen::Index>(width));
      a[0] = 1.0;
      for (std::size_t i = 1; i < width; ++i) {
        a[static_cast<Eigen::Index>(i)] = weights[weight_offsets[p] + i - 1];
      }
      double dot_xy = 0.0;
      for (std::size_t i = 0; i < width; ++i) dot_xy += a[static_cast<Eigen::Index>(i)] * y[i];
      const double e = norms[static_cast<Eigen::Index>(p)] - 2.0 * dot_xy + a.dot(gram[c] * a);
      err[p] = std::max(0.0, e);
    }
  });
  double sum = 0.0;
  for (double e : err) sum += e;
  return sum;
}

}  // namespace prt
