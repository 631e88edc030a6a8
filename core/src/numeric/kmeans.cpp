#include "prtlab/numeric/kmeans.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include "numeric/row_access.h"
#include "prtlab/base/error.h"

namespace prt {

namespace {

using numeric_detail::axpy;
using numeric_detail::dot;
using numeric_detail::squared_norm;

// Doubles built from the generator's bits, because the standard distributions may differ between
// library implementations and the same seed must give the same clusters everywhere.
class SeededRandom {
 public:
  explicit SeededRandom(std::uint64_t seed) : rng_(seed) {}
  double uniform() { return static_cast<double>(rng_() >> 11) * 0x1.0p-53; }

 private:
  std::mt19937_64 rng_;
};

std::vector<double> resolve_weights(std::span<const double> weights, std::size_t m) {
  if (weights.empty()) return std::vector<double>(m, 1.0);
  if (weights.size() != m) {
    throw ParameterError(fmt::format("kmeans: {} weights given for {} points", weights.size(), m));
  }
  double total = 0.0;
  for (std::size_t i = 0; i < m; ++i) {
    if (!std::isfinite(weights[i]) || weights[i] < 0.0) {
      throw ParameterError(fmt::format(
          "kmeans: weight {} of point {} is not a finite non-negative number", weights[i], i));
    }
    total += weights[i];
  }
  if (total <= 0.0) throw ParameterError("kmeans: the weights are all zero");
  return {weights.begin(), weights.end()};
}

template <class Access>
class Lloyd {
 public:
  Lloyd(const Access& a, std::vector<double> weights) : a_(a), w_(std::move(weights)) {
    norms_.resize(a.rows());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, a.rows(), 256), [&](const auto& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) norms_[i] = squared_norm(a_, i);
    });
    assignments_.assign(a.rows(), 0);
    distances_.assign(a.rows(), 0.0);
  }

  std::size_t rows() const { return a_.rows(); }
  std::size_t cols() const { return a_.cols(); }
  const std::vector<double>& weights() const { return w_; }
  const std::vector<std::uint32_t>& assignments() const { return assignments_; }
  const std::vector<double>& distances() const { return distances_; }

  double distance(std::size_t i, const RowMajorMatrixXd& c, Eigen::Index j, double c_norm) const {
    return std::max(0.0, norms_[i] - 2.0 * dot(a_, i, c.row(j).data()) + c_norm);
  }

  /// Assigns every point to its nearest centroid; returns the number of points that moved.
  std::size_t assign(const RowMajorMatrixXd& c) {
    const Eigen::VectorXd c_norms = c.rowwise().squaredNorm();
    std::vector<unsigned char> moved(rows(), 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows(), 64), [&](const auto& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        double best = std::numeric_limits<double>::infinity();
        std::uint32_t best_j = 0;
        for (Eigen::Index j = 0; j < c.rows(); ++j) {
          const double d = distance(i, c, j, c_norms[j]);
          if (d < best) {
            best = d;
            best_j = static_cast<std::uint32_t>(j);
          }
        }
        moved[i] = assignments_[i] != best_j;
        assignments_[i] = best_j;
        distances_[i] = best;
      }
    });
    return static_cast<std::size_t>(std::count(moved.begin(), moved.end(), 1));
  }

  double squared_error() const {
    double s = 0.0;
    for (std::size_t i = 0; i < rows(); ++i) s += w_[i] * distances_[i];
    return s;
  }

  std::vector<double> cluster_errors(Eigen::Index k) const {
    std::vector<double> e(static_cast<std::size_t>(k), 0.0);
    for (std::size_t i = 0; i < rows(); ++i) e[assignments_[i]] += w_[i] * distances_[i];
    return e;
  }

  std::vector<double> cluster_weights(Eigen::Index k) const {
    std::vector<double> e(static_cast<std::size_t>(k), 0.0);
    for (std::size_t i = 0; i < rows(); ++i) e[assignments_[i]] += w_[i];
    return e;
  }

  /// Moves each centroid to the weighted mean of its points. A centroid whose points weigh
  /// nothing is moved onto the point farthest from its own centroid: that point's error drops
  /// to zero and no other point's grows, so the error still cannot increase.
  void update(RowMajorMatrixXd& c) {
    const Eigen::Index k = c.rows();
    const std::vector<double> weight = cluster_weights(k);
    RowMajorMatrixXd sums = RowMajorMatrixXd::Zero(k, c.cols());
    for (std::size_t i = 0; i < rows(); ++i) {
      if (w_[i] != 0.0) axpy(a_, i, w_[i], sums.row(assignments_[i]).data());
    }
    std::vector<Eigen::Index> empty;
    for (Eigen::Index j = 0; j < k; ++j) {
      if (weight[static_cast<std::size_t>(j)] > 0.0) {
        c.row(j) = sums.row(j) / weight[static_cast<std::size_t>(j)];
      } else {
        empty.push_back(j);
      }
    }
    if (empty.empty()) return;
    const Eigen::VectorXd c_norms = c.rowwise().squaredNorm();
    std::vector<double> d(rows());
    for (std::size_t i = 0; i < rows(); ++i) {
      d[i] = distance(i, c, assignments_[i], c_norms[assignments_[i]]);
    }
    std::vector<unsigned char> taken(rows(), 0);
    for (const Eigen::Index j : empty) {
      const std::size_t p = farthest(d, taken);
      if (p == rows()) break;
      taken[p] = 1;
      c.row(j).setZero();
      axpy(a_, p, 1.0, c.row(j).data());
    }
  }

  /// Runs up to max_iterations update + assign steps after an initial assignment.
  int run(RowMajorMatrixXd& c, int max_iterations, double tolerance, std::vector<double>* history) {
    assign(c);
    double error = squared_error();
    if (history) history->push_back(error);
    int it = 0;
    while (it < max_iterations) {
      update(c);
      const std::size_t moved = assign(c);
      ++it;
      const double next = squared_error();
      if (history) history->push_back(next);
      const bool stalled = tolerance > 0.0 && error - next <= tolerance * error;
      error = next;
      if (moved == 0 || stalled) break;
    }
    return it;
  }

  void add_point_to(std::size_t i, double alpha, double* out) const { axpy(a_, i, alpha, out); }

 private:
  // Largest weighted distance, then largest plain distance (for zero-weight points), ties to
  // the lower index; rows() when every point sits on a centroid.
  std::size_t farthest(const std::vector<double>& d,
                       const std::vector<unsigned char>& taken) const {
    std::size_t best = rows();
    double best_wd = 0.0;
    for (std::size_t i = 0; i < rows(); ++i) {
      if (!taken[i] && w_[i] * d[i] > best_wd) best_wd = w_[i] * d[i], best = i;
    }
    if (best != rows()) return best;
    double best_d = 0.0;
    for (std::size_t i = 0; i < rows(); ++i) {
      if (!taken[i] && d[i] > best_d) best_d = d[i], best = i;
    }
    return best;
  }

  const Access& a_;
  std::vector<double> w_;
  std::vector<double> norms_;
  std::vector<std::uint32_t> assignments_;
  std::vector<double> distances_;
};

template <class Access>
RowMajorMatrixXd weighted_mean(const Lloyd<Access>& l) {
  RowMajorMatrixXd c = RowMajorMatrixXd::Zero(1, static_cast<Eigen::Index>(l.cols()));
  double total = 0.0;
  for (std::size_t i = 0; i < l.rows(); ++i) {
    if (l.weights()[i] == 0.0) continue;
    l.add_point_to(i, l.weights()[i], c.data());
    total += l.weights()[i];
  }
  return c / total;
}

template <class Access>
int lbg_split(Lloyd<Access>& l, RowMajorMatrixXd& c, const KMeansOptions& o, SeededRandom& rng) {
  c = weighted_mean(l);
  int iterations = 0;
  const auto n = static_cast<Eigen::Index>(l.cols());
  l.assign(c);
  while (c.rows() < o.clusters) {
    const Eigen::Index k = c.rows();
    const std::vector<double> errors = l.cluster_errors(k);
    const std::vector<double> weights = l.cluster_weights(k);
    // Hand out this stage's splits one at a time to the cluster with the most error per piece,
    // so that k need not be a power of two and a cluster that still covers several groups can
    // be cut into more than two in one stage instead of wasting a split on a compact one.
    const Eigen::Index splits = std::min<Eigen::Index>(k, o.clusters - k);
    std::vector<int> pieces(static_cast<std::size_t>(k), 1);
    for (Eigen::Index s = 0; s < splits; ++s) {
      std::size_t best = 0;
      for (std::size_t j = 1; j < pieces.size(); ++j) {
        if (errors[j] * pieces[best] > errors[best] * pieces[j]) best = j;
      }
      ++pieces[best];
    }
    c.conservativeResize(k + splits, Eigen::NoChange);
    Eigen::Index next = k;
    for (Eigen::Index j = 0; j < k; ++j) {
      const int p = pieces[static_cast<std::size_t>(j)];
      if (p == 1) continue;
      const double w = weights[static_cast<std::size_t>(j)];
      double radius = w > 0.0 ? std::sqrt(errors[static_cast<std::size_t>(j)] / w) : 0.0;
      if (radius == 0.0) radius = c.row(j).norm() + 1.0;
      const Eigen::RowVectorXd centre = c.row(j);
      auto perturbation = [&]() {
        Eigen::RowVectorXd delta(n);
        for (Eigen::Index d = 0; d < n; ++d) delta[d] = 2.0 * rng.uniform() - 1.0;
        const double len = delta.norm();
        return Eigen::RowVectorXd(delta * (len > 0.0 ? o.split_perturbation * radius / len : 0.0));
      };
      // Two pieces are the classic LBG pair c +- delta; more pieces add further random offsets.
      const Eigen::RowVectorXd delta = perturbation();
      c.row(j) = centre - delta;
      c.row(next++) = centre + delta;
      for (int extra = 2; extra < p; ++extra) c.row(next++) = centre + perturbation();
    }
    if (c.rows() < o.clusters) iterations += l.run(c, o.split_iterations, o.tolerance, nullptr);
  }
  return iterations;
}

template <class Access>
void plus_plus(Lloyd<Access>& l, RowMajorMatrixXd& c, const KMeansOptions& o, SeededRandom& rng) {
  const std::size_t m = l.rows();
  const std::vector<double>& w = l.weights();
  std::vector<double> d(m, std::numeric_limits<double>::infinity());
  c = RowMajorMatrixXd::Zero(o.clusters, static_cast<Eigen::Index>(l.cols()));
  // Draws an index with probability proportional to score; the last positive one absorbs the
  // rounding of the running sum.
  auto draw = [&](const std::vector<double>& score) {
    const double total = std::accumulate(score.begin(), score.end(), 0.0);
    if (!(total > 0.0)) return std::size_t{0};
    const double target = rng.uniform() * total;
    double run = 0.0;
    std::size_t last = 0;
    for (std::size_t i = 0; i < m; ++i) {
      if (score[i] <= 0.0) continue;
      last = i;
      run += score[i];
      if (run > target) return i;
    }
    return last;
  };
  std::vector<double> score(w);
  for (Eigen::Index j = 0; j < o.clusters; ++j) {
    const std::size_t p = draw(score);
    l.add_point_to(p, 1.0, c.row(j).data());
    const double cn = c.row(j).squaredNorm();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 256), [&](const auto& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        d[i] = std::min(d[i], l.distance(i, c, j, cn));
        score[i] = w[i] * d[i];
      }
    });
  }
}

void check_common(const RowSet& points, const KMeansOptions& o) {
  if (o.max_iterations < 0 || o.split_iterations < 0 || !(o.tolerance >= 0.0) ||
      !(o.split_perturbation > 0.0)) {
    throw ParameterError(
        "kmeans: iterations must be >= 0, tolerance >= 0 and split_perturbation > 0");
  }
  if (points.rows() == 0) throw ParameterError("kmeans: there are no points");
}

template <class Access>
KMeansResult finish(Lloyd<Access>& l, const RowMajorMatrixXd& c, int iterations,
                    std::vector<double> history) {
  KMeansResult r;
  r.assignments = l.assignments();
  r.centroids = c;
  r.counts.assign(static_cast<std::size_t>(c.rows()), 0);
  for (const std::uint32_t a : r.assignments) ++r.counts[a];
  r.squared_error = l.squared_error();
  r.iterations = iterations;
  r.squared_error_history = std::move(history);
  return r;
}

}  // namespace

KMeansResult kmeans(const RowSet& points, const KMeansOptions& options) {
  check_common(points, options);
  if (options.clusters < 1 || static_cast<std::size_t>(options.clusters) > points.rows()) {
    throw ParameterError(fmt::format("kmeans: {} clusters asked of {} points (need 1..{})",
                                     options.clusters, points.rows(), points.rows()));
  }
  std::vector<double> w = resolve_weights(options.weights, points.rows());
  return numeric_detail::visit_rows(points, [&](const auto& a) {
    Lloyd l(a, std::move(w));
    SeededRandom rng(options.seed);
    RowMajorMatrixXd c;
    int iterations = 0;
    if (options.init == KMeansInit::kLbgSplitting) {
      iterations = lbg_split(l, c, options, rng);
    } else {
      plus_plus(l, c, options, rng);
    }
    std::vector<double> history;
    iterations += l.run(c, options.max_iterations, options.tolerance, &history);
    return finish(l, c, iterations, std::move(history));
  });
}

KMeansResult kmeans_from(const RowSet& points, const Eigen::MatrixXd& initial_centroids,
                         const KMeansOptions& options) {
  check_common(points, options);
  if (initial_centroids.rows() < 1 ||
      static_cast<std::size_t>(initial_centroids.cols()) != points.cols()) {
    throw ParameterError(
        fmt::format("kmeans_from: {} x {} initial centroids for points of dimension {}",
                    initial_centroids.rows(), initial_centroids.cols(), points.cols()));
  }
  std::vector<double> w = resolve_weights(options.weights, points.rows());
  return numeric_detail::visit_rows(points, [&](const auto& a) {
    Lloyd l(a, std::move(w));
    RowMajorMatrixXd c = initial_centroids;
    std::vector<double> history;
    const int iterations = l.run(c, options.max_iterations, options.tolerance, &history);
    return finish(l, c, iterations, std::move(history));
  });
}

NearestCentroids nearest_centroids(const RowSet& points, const Eigen::MatrixXd& centroids) {
  if (centroids.rows() < 1 || static_cast<std::size_t>(centroids.cols()) != points.cols()) {
    throw ParameterError(fmt::format("nearest_centroids: {} x {} centroids for dimension {}",
                                     centroids.rows(), centroids.cols(), points.cols()));
  }
  return numeric_detail::visit_rows(points, [&](const auto& a) {
    Lloyd l(a, std::vector<double>(points.rows(), 1.0));
    l.assign(RowMajorMatrixXd(centroids));
    return NearestCentroids{l.assignments(), l.distances()};
  });
}

}  // namespace prt
