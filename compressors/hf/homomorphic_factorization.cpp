#include "hf/homomorphic_factorization.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/btf/halfway_parameterization.h"

namespace prt::hf {
namespace {

using Triplets = std::vector<Eigen::Triplet<double>>;

// lambda times the 5-point Laplacian of a side x side grid (zero normal derivative at the
// edges: a cell's row is its neighbour count minus its neighbours), rows from `row`, unknowns
// from `col`.
void add_laplacian(Triplets& t, int& row, int col, int side, double lambda) {
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) {
      int n = 0;
      const auto add = [&](int xx, int yy) {
        if (xx < 0 || yy < 0 || xx >= side || yy >= side) return;
        t.emplace_back(row, col + yy * side + xx, -lambda);
        ++n;
      };
      add(x - 1, y);
      add(x + 1, y);
      add(x, y - 1);
      add(x, y + 1);
      t.emplace_back(row, col + y * side + x, lambda * n);
      ++row;
    }
}

}  // namespace

HomomorphicFactorization::HomomorphicFactorization(const HomomorphicOptions& options)
    : o_(options) {
  PRT_CHECK(o_.light_side >= 1 && o_.view_side >= 1 && o_.half_side >= 1, "hf: grid sides");
  PRT_CHECK(o_.lambda > 0 && o_.floor > 0 && o_.floor < 1 && o_.refine >= 0,
            "hf: lambda > 0, 0 < floor < 1, refine >= 0");
  const int m = light_count(), h = half_count(), v = view_count(), n = m + h + v;
  const auto w = halfway_weights(o_.light_side, o_.view_side, o_.half_side);
  Triplets data;
  for (int s = 0; s < m * v; ++s) {
    data.emplace_back(s, s % m, 1.0);
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator i(w, s); i; ++i)
      data.emplace_back(s, m + static_cast<int>(i.col()), i.value());
    data.emplace_back(s, m + h + s / m, 1.0);
  }
  data_rows_.resize(m * v, n);
  data_rows_.setFromTriplets(data.begin(), data.end());

  Triplets all = data;
  int row = m * v;
  add_laplacian(all, row, 0, o_.light_side, o_.lambda);
  add_laplacian(all, row, m, o_.half_side, o_.lambda);
  add_laplacian(all, row, m + h, o_.view_side, o_.lambda);
  for (int a = 0; a < h; ++a) all.emplace_back(row, m + a, 1.0);
  ++row;
  for (int e = 0; e < v; ++e) all.emplace_back(row, m + h + e, 1.0);
  ++row;
  Eigen::SparseMatrix<double> a(row, n);
  a.setFromTriplets(all.begin(), all.end());
  Triplets reg;
  for (const auto& t : all)
    if (t.row() >= m * v) reg.emplace_back(t.row() - m * v, t.col(), t.value());
  regulariser_.resize(row - m * v, n);
  regulariser_.setFromTriplets(reg.begin(), reg.end());
  regulariser_normal_ = Eigen::MatrixXd(regulariser_.transpose() * regulariser_);
  const Eigen::SparseMatrix<double> normal = a.transpose() * a;
  solver_.compute(normal);
  if (solver_.info() != Eigen::Success)
    throw Error(fmt::format(
        "hf: the normal matrix of the log system (light side {}, view side {}, half side {}, "
        "lambda {}) is singular",
        o_.light_side, o_.view_side, o_.half_side, o_.lambda));
}

void HomomorphicFactorization::solve_log(std::span<const double> y, std::span<double> x) const {
  const Eigen::Map<const Eigen::VectorXd> yv(y.data(), static_cast<Eigen::Index>(y.size()));
  const Eigen::VectorXd rhs = data_rows_.transpose() * yv;
  Eigen::Map<Eigen::VectorXd>(x.data(), static_cast<Eigen::Index>(x.size())) = solver_.solve(rhs);
}

double HomomorphicFactorization::linear_objective(std::span<const double> f,
                                                  std::span<const double> x) const {
  const Eigen::Map<const Eigen::VectorXd> xv(x.data(), static_cast<Eigen::Index>(x.size()));
  const Eigen::Map<const Eigen::VectorXd> fv(f.data(), static_cast<Eigen::Index>(f.size()));
  const Eigen::VectorXd model = (data_rows_ * xv).array().exp().matrix();
  // The regulariser rows weighted by the samples' mean square: a data row's residual relative to
  // the data then weighs against a regulariser row in log units as in the log fit.
  const double weight = fv.squaredNorm() / static_cast<double>(fv.size());
  return (model - fv).squaredNorm() + weight * (regulariser_ * xv).squaredNorm();
}

double HomomorphicFactorization::refine_linear(std::span<const double> f, std::span<double> x,
                                               int iterations) const {
  const auto n = static_cast<Eigen::Index>(x.size());
  Eigen::Map<Eigen::VectorXd> xv(x.data(), n);
  const Eigen::Map<const Eigen::VectorXd> fv(f.data(), static_cast<Eigen::Index>(f.size()));
  double objective = linear_objective(f, x);
  const double weight = fv.squaredNorm() / static_cast<double>(fv.size());
  if (!(weight > 0)) return objective;
  for (int it = 0; it < iterations; ++it) {
    // J = diag(g) A for g = exp(A x): the Gauss-Newton matrix J^T J + R^T R and the gradient
    // J^T (g - f) + R^T R x.
    const Eigen::VectorXd g = (data_rows_ * xv).array().exp().matrix();
    Eigen::MatrixXd h = weight * regulariser_normal_;
    Eigen::VectorXd grad = weight * (regulariser_normal_ * xv);
    for (Eigen::Index s = 0; s < data_rows_.rows(); ++s) {
      const double gs = g[s], rs = gs * (gs - fv[s]);
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator i(data_rows_, s); i; ++i) {
        grad[i.col()] += rs * i.value();
        for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator k(data_rows_, s); k; ++k)
          h(i.col(), k.col()) += gs * gs * i.value() * k.value();
      }
    }
    const Eigen::VectorXd step = h.ldlt().solve(-grad);
    if (!step.allFinite()) break;
    bool better = false;
    for (double t = 1.0; t > 1e-4; t *= 0.5) {
      const Eigen::VectorXd trial = xv + t * step;
      const double value = linear_objective(
          f, std::span<const double>(trial.data(), static_cast<std::size_t>(trial.size())));
      if (value < objective) {
        xv = trial;
        objective = value;
        better = true;
        break;
      }
    }
    if (!better) break;
  }
  return objective;
}

void HomomorphicFactorization::factor(std::span<const double> f, std::span<double> p,
                                      std::span<double> q, std::span<double> r) const {
  const int m = light_count(), h = half_count(), v = view_count();
  const double peak = *std::max_element(f.begin(), f.end());
  if (!(peak > 0)) {
    std::fill(p.begin(), p.end(), 0.0);
    std::fill(q.begin(), q.end(), 0.0);
    std::fill(r.begin(), r.end(), 0.0);
    return;
  }
  const double floor = o_.floor * peak;
  std::vector<double> y(f.size()), x(static_cast<std::size_t>(m + h + v));
  for (std::size_t s = 0; s < f.size(); ++s) y[s] = std::log(std::max(f[s], floor));
  solve_log(y, x);
  if (o_.refine > 0) refine_linear(f, x, o_.refine);
  for (int j = 0; j < m; ++j) p[j] = std::exp(x[j]);
  for (int a = 0; a < h; ++a) q[a] = std::exp(x[m + a]);
  for (int e = 0; e < v; ++e) r[e] = std::exp(x[m + h + e]);
}

}  // namespace prt::hf
