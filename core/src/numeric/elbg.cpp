#include "prtlab/numeric/elbg.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "prtlab/base/error.h"
#include "prtlab/numeric/kmeans.h"
#include "prtlab/numeric/row_set.h"

namespace prt {
namespace {

using PointMatrix =
    Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;

class Quantiser {
 public:
  Quantiser(PointMatrix x, Eigen::MatrixXd centroids, const ElbgOptions& o)
      : x_(x), c_(std::move(centroids)), o_(o), rng_(o.seed ^ 0x9e3779b97f4a7c15ull) {
    assign_.assign(static_cast<std::size_t>(x_.rows()), 0);
  }

  /// Nearest codeword of every point (ties to the lower index), then every codeword to the mean
  /// of its cell (an empty cell keeps its codeword). Returns the distortion after both.
  double lloyd_pass() {
    const auto k = static_cast<Eigen::Index>(c_.rows());
    const Eigen::VectorXd cn = c_.rowwise().squaredNorm();
    constexpr Eigen::Index kBlock = 512;
    const Eigen::Index n = x_.rows();
    tbb::parallel_for(
        tbb::blocked_range<Eigen::Index>(0, n, kBlock),
        [&](const auto& r) {
          // Double products, so that the assignment is the nearest codeword in the distortion's
          // own arithmetic and a Lloyd pass never raises it.
          const Eigen::MatrixXd dots =
              x_.middleRows(r.begin(), r.end() - r.begin()).template cast<double>() *
              c_.transpose();
          for (Eigen::Index i = r.begin(); i < r.end(); ++i) {
            double best = std::numeric_limits<double>::infinity();
            std::uint32_t arg = 0;
            for (Eigen::Index c = 0; c < k; ++c) {
              const double d = cn[c] - 2.0 * dots(i - r.begin(), c);
              if (d < best) best = d, arg = static_cast<std::uint32_t>(c);
            }
            assign_[static_cast<std::size_t>(i)] = arg;
          }
        },
        tbb::simple_partitioner());  // fixed blocks: the same products on any thread count
    update_centroids();
    return distortion();
  }

  /// ELBG's shift attempts over the current cells; returns how many were tried and accepted.
  std::pair<int, int> shift_attempts() {
    const auto k = static_cast<std::size_t>(c_.rows());
    if (k < 3) return {0, 0};
    build_cells();
    std::vector<double> d(k, 0.0);
    for (std::size_t c = 0; c < k; ++c) d[c] = cell_distortion(cells_[c], c_.row(c));
    const double mean = std::accumulate(d.begin(), d.end(), 0.0) / static_cast<double>(k);
    std::vector<std::size_t> low, high;
    for (std::size_t c = 0; c < k; ++c) (d[c] < mean ? low : high).push_back(c);
    std::sort(low.begin(), low.end(), [&](auto a, auto b) { return d[a] < d[b]; });
    std::sort(high.begin(), high.end(), [&](auto a, auto b) { return d[a] > d[b]; });
    std::vector<char> used(k, 0);
    int tried = 0, accepted = 0;
    std::size_t next_high = 0;
    for (std::size_t i : low) {
      if (used[i]) continue;
      while (next_high < high.size() && used[high[next_high]]) ++next_high;
      if (next_high >= high.size()) break;
      const std::size_t p = high[next_high];
      if (cells_[p].size() < 2 || !(d[p] > mean)) break;
      const std::size_t l = nearest_other(i, p);
      if (l == k || used[l]) continue;
      ++tried;
      // The abandoned cell goes to its nearest codeword.
      std::vector<std::uint32_t> merged = cells_[i];
      merged.insert(merged.end(), cells_[l].begin(), cells_[l].end());
      const Eigen::RowVectorXd yl = mean_of(merged, c_.row(l));
      const double dl = cell_distortion(merged, yl);
      // Two codewords on the principal axis of the busy cell, refined by local Lloyd iterations.
      Eigen::RowVectorXd ya, yb;
      std::vector<std::uint32_t> ca, cb;
      const double dp = split(cells_[p], ya, yb, ca, cb);
      if (dl + dp < d[i] + d[p] + d[l]) {
        ++accepted;
        c_.row(l) = yl;
        c_.row(i) = ya;
        c_.row(p) = yb;
        for (std::uint32_t m : merged) assign_[m] = static_cast<std::uint32_t>(l);
        for (std::uint32_t m : ca) assign_[m] = static_cast<std::uint32_t>(i);
        for (std::uint32_t m : cb) assign_[m] = static_cast<std::uint32_t>(p);
        used[i] = used[p] = used[l] = 1;
        ++next_high;
      }
    }
    return {tried, accepted};
  }

  double distortion() const {
    double total = 0;
    for (Eigen::Index i = 0; i < x_.rows(); ++i)
      total +=
          (x_.row(i).cast<double>() - c_.row(assign_[static_cast<std::size_t>(i)])).squaredNorm();
    return total;
  }

  ElbgResult result(double initial, std::vector<double> history, int rounds, int tried,
                    int accepted) const {
    ElbgResult r;
    r.assignments = assign_;
    r.centroids = c_;
    r.counts.assign(static_cast<std::size_t>(c_.rows()), 0);
    for (std::uint32_t a : assign_) ++r.counts[a];
    r.squared_error = distortion();
    r.initial_squared_error = initial;
    r.rounds = rounds;
    r.shifts_tried = tried;
    r.shifts_accepted = accepted;
    r.squared_error_history = std::move(history);
    return r;
  }

 private:
  void build_cells() {
    cells_.assign(static_cast<std::size_t>(c_.rows()), {});
    for (std::size_t i = 0; i < assign_.size(); ++i)
      cells_[assign_[i]].push_back(static_cast<std::uint32_t>(i));
  }

  void update_centroids() {
    build_cells();
    tbb::parallel_for(std::size_t{0}, cells_.size(), [&](std::size_t c) {
      if (!cells_[c].empty()) c_.row(static_cast<Eigen::Index>(c)) = mean_of(cells_[c], c_.row(c));
    });
  }

  Eigen::RowVectorXd mean_of(const std::vector<std::uint32_t>& cell,
                             const Eigen::RowVectorXd& fallback) const {
    if (cell.empty()) return fallback;
    Eigen::RowVectorXd s = Eigen::RowVectorXd::Zero(x_.cols());
    for (std::uint32_t m : cell) s += x_.row(m).cast<double>();
    return s / static_cast<double>(cell.size());
  }

  double cell_distortion(const std::vector<std::uint32_t>& cell,
                         const Eigen::RowVectorXd& y) const {
    double s = 0;
    for (std::uint32_t m : cell) s += (x_.row(m).cast<double>() - y).squaredNorm();
    return s;
  }

  /// The codeword nearest to codeword i other than i and `skip`; k when there is none.
  std::size_t nearest_other(std::size_t i, std::size_t skip) const {
    const auto k = static_cast<std::size_t>(c_.rows());
    std::size_t best = k;
    double bd = std::numeric_limits<double>::infinity();
    for (std::size_t c = 0; c < k; ++c) {
      if (c == i || c == skip) continue;
      const double dd = (c_.row(c) - c_.row(i)).squaredNorm();
      if (dd < bd) bd = dd, best = c;
    }
    return best;
  }

  double split(const std::vector<std::uint32_t>& cell, Eigen::RowVectorXd& ya,
               Eigen::RowVectorXd& yb, std::vector<std::uint32_t>& ca,
               std::vector<std::uint32_t>& cb) {
    const Eigen::RowVectorXd mu = mean_of(cell, Eigen::RowVectorXd::Zero(x_.cols()));
    const auto n = static_cast<Eigen::Index>(cell.size());
    // Row-major: the rows are written and read whole.
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> centred(n, x_.cols());
    for (Eigen::Index j = 0; j < n; ++j)
      centred.row(j) = x_.row(cell[static_cast<std::size_t>(j)]).cast<double>() - mu;
    const Eigen::VectorXd norms = centred.rowwise().squaredNorm();
    // A few power steps on the scatter C^T C, through the cell's (few) rows: the axis only
    // places the two starting codewords, which the local Lloyd iterations then refine.
    std::normal_distribution<double> normal;
    Eigen::VectorXd v(x_.cols());
    for (Eigen::Index j = 0; j < v.size(); ++j) v[j] = normal(rng_);
    double lambda = 0;
    for (int it = 0; it < 6; ++it) {
      const Eigen::VectorXd w = centred.transpose() * (centred * v);
      lambda = w.norm();
      if (!(lambda > 0)) break;
      v = w / lambda;
    }
    const double spread = std::sqrt(lambda / static_cast<double>(n));
    // Codewords relative to mu, as columns; distances ||c_i - a||^2 = |c_i|^2 - 2 c_i.a + |a|^2.
    Eigen::MatrixXd ab(x_.cols(), 2);
    ab.col(0) = -spread * v;
    ab.col(1) = spread * v;
    std::vector<char> side(cell.size(), 0);
    for (int it = 0; it <= o_.local_iterations; ++it) {
      const Eigen::MatrixXd dots = centred * ab;
      const double na = ab.col(0).squaredNorm(), nb = ab.col(1).squaredNorm();
      for (Eigen::Index j = 0; j < n; ++j)
        side[static_cast<std::size_t>(j)] = na - 2 * dots(j, 0) > nb - 2 * dots(j, 1);
      if (it == o_.local_iterations) break;
      Eigen::MatrixXd pick = Eigen::MatrixXd::Zero(n, 2);  // the cell means as centred^T pick
      Eigen::Index counts[2] = {0, 0};
      for (Eigen::Index j = 0; j < n; ++j)
        ++counts[static_cast<int>(side[static_cast<std::size_t>(j)])];
      for (Eigen::Index j = 0; j < n; ++j) {
        const int s = side[static_cast<std::size_t>(j)];
        pick(j, s) = 1.0 / static_cast<double>(counts[s]);
      }
      const Eigen::MatrixXd means = centred.transpose() * pick;
      for (int s = 0; s < 2; ++s)
        if (counts[s] > 0) ab.col(s) = means.col(s);
    }
    ca.clear();
    cb.clear();
    double d = 0;
    const Eigen::MatrixXd dots = centred * ab;
    for (Eigen::Index j = 0; j < n; ++j) {
      const int s = side[static_cast<std::size_t>(j)];
      (s ? cb : ca).push_back(cell[static_cast<std::size_t>(j)]);
      d += norms[j] - 2 * dots(j, s) + ab.col(s).squaredNorm();
    }
    ya = mu + ab.col(0).transpose();
    yb = mu + ab.col(1).transpose();
    return std::max(0.0, d);
  }

  PointMatrix x_;
  Eigen::MatrixXd c_;
  const ElbgOptions& o_;
  std::mt19937_64 rng_;
  std::vector<std::uint32_t> assign_;
  std::vector<std::vector<std::uint32_t>> cells_;
};

void check_points(std::span<const float> points, std::size_t rows, std::size_t cols, int clusters) {
  if (points.size() != rows * cols)
    throw ParameterError(
        fmt::format("elbg: {} values for {} points of dimension {}", points.size(), rows, cols));
  if (clusters < 1 || static_cast<std::size_t>(clusters) > rows)
    throw ParameterError(fmt::format("elbg: {} clusters for {} points", clusters, rows));
  if (!std::all_of(points.begin(), points.end(), [](float v) { return std::isfinite(v); }))
    throw ParameterError("elbg: a point has a value that is not finite");
}

ElbgResult run(PointMatrix x, Eigen::MatrixXd centroids, const ElbgOptions& o) {
  Quantiser q(x, std::move(centroids), o);
  const double initial = q.lloyd_pass();
  std::vector<double> history;
  double previous = initial;
  int rounds = 0, tried = 0, accepted = 0;
  for (; rounds < o.rounds; ++rounds) {
    const auto [t, a] = q.shift_attempts();
    tried += t;
    accepted += a;
    const double now = q.lloyd_pass();
    history.push_back(now);
    if (!(previous > 0) || (previous - now) <= o.tolerance * previous) {
      ++rounds;
      break;
    }
    previous = now;
  }
  return q.result(initial, std::move(history), rounds, tried, accepted);
}

}  // namespace

ElbgResult elbg(std::span<const float> points, std::size_t rows, std::size_t cols,
                const ElbgOptions& options) {
  check_points(points, rows, cols, options.clusters);
  KMeansOptions k;
  k.clusters = options.clusters;
  k.init = KMeansInit::kPlusPlus;
  k.seed = options.seed;
  k.max_iterations = options.initial_iterations;
  const KMeansResult start = kmeans(RowSet::dense(points, rows, cols), k);
  return run(
      PointMatrix(points.data(), static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(cols)),
      start.centroids, options);
}

ElbgResult elbg_from(std::span<const float> points, std::size_t rows, std::size_t cols,
                     const Eigen::MatrixXd& initial_centroids, const ElbgOptions& options) {
  ElbgOptions o = options;
  o.clusters = static_cast<int>(initial_centroids.rows());
  check_points(points, rows, cols, o.clusters);
  if (static_cast<std::size_t>(initial_centroids.cols()) != cols)
    throw ParameterError(fmt::format("elbg: centroids of dimension {} for points of dimension {}",
                                     initial_centroids.cols(), cols));
  return run(
      PointMatrix(points.data(), static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(cols)),
      initial_centroids, o);
}

}  // namespace prt
