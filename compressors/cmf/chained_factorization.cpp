#include "cmf/chained_factorization.h"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <vector>

#include "prtlab/base/error.h"

namespace prt::cmf {
namespace {

// Power iterations stop when the singular value changes by less than this, relatively.
constexpr double kPowerTolerance = 1e-13;
constexpr int kPowerIterations = 500;
// Alternations of the masked rank-1 fit of step 2 (`halfway = svd`).
constexpr int kMaskedRankOneIterations = 30;
// Q's refinement is pulled towards its previous value with this weight, relative to the
// normal matrix's largest diagonal entry, so that halfway cells no sample reaches keep the
// chain's value instead of falling to 0.
constexpr double kRefineAnchor = 1e-10;
// Alternating sweeps of step 3's K-term split (terms > 1).
constexpr int kTermSweeps = 50;
// Coordinate-descent sweeps of the non-negative Q step, and the relative change that ends them.
constexpr int kQSweeps = 30;
constexpr double kQTolerance = 1e-6;

double norm(std::span<const double> x) {
  double s = 0;
  for (double v : x) s += v * v;
  return std::sqrt(s);
}

// Coordinate descent on min x^T A x - 2 b^T x subject to x >= 0 (A symmetric positive
// definite), from a feasible x; each step is the exact minimiser along its coordinate, so the
// objective never increases.
void nonnegative_descent(const Eigen::SparseMatrix<double>& a, const Eigen::VectorXd& b,
                         Eigen::VectorXd& x) {
  Eigen::VectorXd ax = a * x;
  const Eigen::VectorXd diag = a.diagonal();
  for (int sweep = 0; sweep < kQSweeps; ++sweep) {
    double change = 0, size = 0;
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      if (!(diag[i] > 0)) continue;
      const double next = std::max(x[i] - (ax[i] - b[i]) / diag[i], 0.0), delta = next - x[i];
      if (delta == 0) continue;
      for (Eigen::SparseMatrix<double>::InnerIterator it(a, i); it; ++it)
        ax[it.row()] += delta * it.value();
      x[i] = next;
      change = std::max(change, std::abs(delta));
      size = std::max(size, next);
    }
    if (change <= kQTolerance * size) break;
  }
}

}  // namespace

void fit_terms(std::span<const double> target, std::span<const double> w, int terms,
               std::span<double> p, std::span<double> r, int sweeps) {
  const int m = static_cast<int>(p.size()) / terms, v = static_cast<int>(r.size()) / terms;
  PRT_CHECK(terms >= 1 && p.size() == static_cast<std::size_t>(terms) * m &&
                r.size() == static_cast<std::size_t>(terms) * v &&
                target.size() == static_cast<std::size_t>(m) * v &&
                (w.empty() || w.size() == target.size()),
            "cmf: fit_terms sizes");
  const auto weight = [&](std::size_t s) { return w.empty() ? 1.0 : w[s]; };
  // What the other terms leave of sample s for term k (the sample itself when K = 1).
  const auto left = [&](int k, int j, int e) {
    const std::size_t s = static_cast<std::size_t>(e) * m + j;
    double t = target[s];
    if (terms > 1) {
      double others = 0;
      for (int l = 0; l < terms; ++l)
        if (l != k)
          others += p[static_cast<std::size_t>(l) * m + j] * r[static_cast<std::size_t>(l) * v + e];
      t -= weight(s) * others;
    }
    return t;
  };
  // Each entry of one factor of term k (P_k on the light side, else R_k) set to its exact
  // non-negative minimiser with everything else fixed.
  const auto solve = [&](int k, bool light_side) {
    double* x = light_side ? p.data() + static_cast<std::size_t>(k) * m
                           : r.data() + static_cast<std::size_t>(k) * v;
    const double* y = light_side ? r.data() + static_cast<std::size_t>(k) * v
                                 : p.data() + static_cast<std::size_t>(k) * m;
    const int nx = light_side ? m : v, ny = light_side ? v : m;
    for (int a = 0; a < nx; ++a) {
      double num = 0, den = 0;
      for (int c = 0; c < ny; ++c) {
        const int j = light_side ? a : c, e = light_side ? c : a;
        const double b = y[c] * weight(static_cast<std::size_t>(e) * m + j);
        num += left(k, j, e) * b;
        den += b * b;
      }
      if (den > 0) x[a] = std::max(num / den, 0.0);
    }
  };
  for (int it = 0; it < sweeps; ++it) {
    for (int k = 0; k < terms; ++k) solve(k, true);
    for (int k = 0; k < terms; ++k) solve(k, false);
  }
}

void rank_one(std::span<const double> a, int rows, int cols, std::span<double> u,
              std::span<double> v) {
  std::vector<double> vv(static_cast<std::size_t>(cols), 0.0), uu(static_cast<std::size_t>(rows));
  for (int c = 0; c < cols; ++c)
    for (int r = 0; r < rows; ++r) vv[c] += a[static_cast<std::size_t>(c) * rows + r];
  double sigma = 0;
  for (int it = 0; it < kPowerIterations; ++it) {
    const double nv = norm(vv);
    if (nv == 0) break;
    for (double& x : vv) x /= nv;
    std::fill(uu.begin(), uu.end(), 0.0);
    for (int c = 0; c < cols; ++c)
      for (int r = 0; r < rows; ++r) uu[r] += a[static_cast<std::size_t>(c) * rows + r] * vv[c];
    const double nu = norm(uu);
    if (nu == 0) break;
    for (double& x : uu) x /= nu;
    for (int c = 0; c < cols; ++c) {
      double s = 0;
      for (int r = 0; r < rows; ++r) s += a[static_cast<std::size_t>(c) * rows + r] * uu[r];
      vv[c] = s;
    }
    const double next = norm(vv);
    const bool done = std::abs(next - sigma) <= kPowerTolerance * next;
    sigma = next;
    if (done) break;
  }
  const double root = std::sqrt(sigma);
  for (int r = 0; r < rows; ++r) u[r] = std::max(uu[r], 0.0) * root;
  for (int c = 0; c < cols; ++c) v[c] = sigma > 0 ? std::max(vv[c], 0.0) / root : 0.0;
}

ChainedFactorization::ChainedFactorization(const ChainOptions& options) : o_(options) {
  PRT_CHECK(o_.light_side >= 1 && o_.view_side >= 1 && o_.half_side >= 1 && o_.diff_side >= 1 &&
                o_.terms >= 1,
            "cmf: grid sides and terms must be positive");
  gshd_ = gshd_resampling(o_.light_side, o_.view_side, o_.half_side, o_.diff_side);
  w_ = halfway_weights(o_.light_side, o_.view_side, o_.half_side);
  wt_ = w_.transpose();
  w_colsum_ = wt_ * Eigen::VectorXd::Ones(w_.rows());
  if (o_.refine == 0) return;
  const int h = half_count();
  std::vector<Eigen::Triplet<double>> t;
  for (int a = 0; a < h; ++a) t.emplace_back(a, a, 1.0);
  for (int s = 0; s < w_.rows(); ++s)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator i(w_, s); i; ++i)
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator k(w_, s); k; ++k)
        if (i.col() >= k.col())
          t.emplace_back(static_cast<int>(i.col()), static_cast<int>(k.col()), 1.0);
  normal_pattern_.resize(h, h);
  normal_pattern_.setFromTriplets(t.begin(), t.end());
  normal_pattern_.makeCompressed();
  const auto slot = [&](int row, int col) {
    const int* begin = normal_pattern_.innerIndexPtr() + normal_pattern_.outerIndexPtr()[col];
    const int* end = normal_pattern_.innerIndexPtr() + normal_pattern_.outerIndexPtr()[col + 1];
    return static_cast<int>(std::lower_bound(begin, end, row) - normal_pattern_.innerIndexPtr());
  };
  sample_begin_.push_back(0);
  for (int s = 0; s < w_.rows(); ++s) {
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator i(w_, s); i; ++i)
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator k(w_, s); k; ++k)
        if (i.col() >= k.col())
          sample_slot_.push_back(slot(static_cast<int>(i.col()), static_cast<int>(k.col())));
    sample_begin_.push_back(static_cast<int>(sample_slot_.size()));
  }
  for (int a = 0; a < h; ++a) sample_slot_.push_back(slot(a, a));  // the diagonal, for the anchor
}

void ChainedFactorization::factor(std::span<const double> f, std::span<double> p,
                                  std::span<double> q, std::span<double> r) const {
  const int m = light_count(), v = view_count(), h = half_count();
  const auto terms = static_cast<std::size_t>(o_.terms);
  PRT_CHECK(f.size() == static_cast<std::size_t>(m) * v && p.size() == terms * m &&
                q.size() == static_cast<std::size_t>(h) && r.size() == terms * v,
            "cmf: factor sizes");
  const Eigen::Map<const Eigen::VectorXd> fv(f.data(), static_cast<Eigen::Index>(f.size()));
  const double f_mean = fv.mean();

  if (o_.halfway == HalfwayRule::kProject) {
    const Eigen::VectorXd proj = wt_ * fv;
    for (int a = 0; a < h; ++a) q[a] = w_colsum_[a] > 0 ? proj[a] / w_colsum_[a] : f_mean;
  } else {
    halfway_from_gshd(fv, q);
  }
  // Without step 4 the further terms of step 3 join in step 3's domain (the samples divided by
  // Q); with it, each joins the refined chain of the terms before it, in the original samples.
  divide_and_split(f, p, q, r, o_.refine == 0 ? o_.terms : 1);
  if (o_.refine == 0) return;
  refine(f, p, q, r, 1);
  for (int k = 1; k < o_.terms; ++k) {
    const Eigen::VectorXd q_io = w_ * Eigen::Map<const Eigen::VectorXd>(q.data(), h);
    add_term(f, std::span<const double>(q_io.data(), static_cast<std::size_t>(q_io.size())), k, p,
             r);
    refine(f, p, q, r, k + 1);
  }
}

void ChainedFactorization::halfway_from_gshd(const Eigen::Ref<const Eigen::VectorXd>& fv,
                                             std::span<double> q) const {
  const int h = half_count(), d = o_.diff_side * o_.diff_side;
  const double f_mean = fv.mean();
  // Steps 1 and 2: the halfway factor from the GSHD resampling.
  const Eigen::VectorXd hd = gshd_.weights * fv;
  const auto valid = [&](int a, int b) {
    return gshd_.valid[static_cast<std::size_t>(a) * d + b] != 0;
  };
  if (o_.halfway == HalfwayRule::kMean) {
    for (int a = 0; a < h; ++a) {
      double sum = 0;
      int n = 0;
      for (int b = 0; b < d; ++b)
        if (valid(a, b)) {
          sum += hd[static_cast<Eigen::Index>(a) * d + b];
          ++n;
        }
      q[a] = n > 0 ? sum / n : f_mean;
    }
  } else {
    std::vector<double> u(static_cast<std::size_t>(h), 1.0), w(static_cast<std::size_t>(d), 1.0);
    for (int it = 0; it < kMaskedRankOneIterations; ++it) {
      for (int a = 0; a < h; ++a) {
        double num = 0, den = 0;
        for (int b = 0; b < d; ++b)
          if (valid(a, b)) {
            num += hd[static_cast<Eigen::Index>(a) * d + b] * w[b];
            den += w[b] * w[b];
          }
        u[a] = den > 0 ? num / den : 0.0;
      }
      for (int b = 0; b < d; ++b) {
        double num = 0, den = 0;
        for (int a = 0; a < h; ++a)
          if (valid(a, b)) {
            num += hd[static_cast<Eigen::Index>(a) * d + b] * u[a];
            den += u[a] * u[a];
          }
        w[b] = den > 0 ? num / den : 0.0;
      }
    }
    // Dropping the difference factor: each halfway row keeps the mean of its rank-1 model.
    for (int a = 0; a < h; ++a) {
      double sum = 0;
      int n = 0;
      for (int b = 0; b < d; ++b)
        if (valid(a, b)) {
          sum += w[b];
          ++n;
        }
      q[a] = n > 0 ? std::max(u[a] * sum / n, 0.0) : f_mean;
    }
  }
}

void ChainedFactorization::divide_and_split(std::span<const double> f, std::span<double> p,
                                            std::span<double> q, std::span<double> r,
                                            int terms) const {
  const int m = light_count(), v = view_count(), h = half_count();
  // Step 3: divide Q out in the original samples, rank-1 of the residue.
  const Eigen::Map<const Eigen::VectorXd> qv(q.data(), h);
  const Eigen::VectorXd q_io = w_ * qv;
  const double q_floor = 1e-12 * std::max(qv.maxCoeff(), 0.0);
  std::vector<double> residue(f.size());
  for (std::size_t s = 0; s < f.size(); ++s)
    residue[s] = q_io[static_cast<Eigen::Index>(s)] > q_floor
                     ? f[s] / q_io[static_cast<Eigen::Index>(s)]
                     : 0.0;
  rank_one(residue, m, v, p.first(static_cast<std::size_t>(m)),
           r.first(static_cast<std::size_t>(v)));
  for (int k = 1; k < terms; ++k) add_term(residue, {}, k, p, r);
}

void ChainedFactorization::add_term(std::span<const double> target, std::span<const double> w,
                                    int k, std::span<double> p, std::span<double> r) const {
  const int m = light_count(), v = view_count();
  const auto km = static_cast<std::size_t>(k) * m, kv = static_cast<std::size_t>(k) * v;
  double w_peak = 0;
  for (double x : w) w_peak = std::max(w_peak, x);
  // R_k's start: the rank-1 fit of the positive part of what terms 0 .. k-1 leave, in the units
  // of the factors (divided by the weight).
  std::vector<double> rest(target.size());
  for (std::size_t s = 0; s < rest.size(); ++s) {
    const std::size_t j = s % static_cast<std::size_t>(m), e = s / static_cast<std::size_t>(m);
    double model = 0;
    for (int l = 0; l < k; ++l)
      model += p[static_cast<std::size_t>(l) * m + j] * r[static_cast<std::size_t>(l) * v + e];
    const double ws = w.empty() ? 1.0 : w[s];
    rest[s] = ws > 1e-12 * w_peak ? std::max(target[s] / ws - model, 0.0) : 0.0;
  }
  rank_one(rest, m, v, p.subspan(km, static_cast<std::size_t>(m)),
           r.subspan(kv, static_cast<std::size_t>(v)));
  // P_k from 0, so that the first sweep's P_k is the exact minimiser given R_k and the fit of
  // k + 1 terms starts no worse than that of k terms.
  std::fill(p.begin() + static_cast<std::ptrdiff_t>(km),
            p.begin() + static_cast<std::ptrdiff_t>(km + m), 0.0);
  fit_terms(target, w, k + 1, p.first(km + m), r.first(kv + v), kTermSweeps);
}

void ChainedFactorization::refine(std::span<const double> f, std::span<double> p,
                                  std::span<double> q, std::span<double> r, int terms) const {
  const int m = light_count(), v = view_count(), h = half_count();
  Eigen::SparseMatrix<double> normal = normal_pattern_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver;
  solver.analyzePattern(normal);
  Eigen::Map<Eigen::VectorXd> qv(q.data(), h);
  Eigen::VectorXd rhs(h);
  for (int it = 0; it < o_.refine; ++it) {
    // Q given P and R.
    std::fill(normal.valuePtr(), normal.valuePtr() + normal.nonZeros(), 0.0);
    rhs.setZero();
    for (int s = 0; s < w_.rows(); ++s) {
      double a = p[s % m] * r[s / m];
      for (int k = 1; k < terms; ++k)
        a +=
            p[static_cast<std::size_t>(k) * m + s % m] * r[static_cast<std::size_t>(k) * v + s / m];
      const double a2 = a * a;
      int slot = sample_begin_[s];
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator i(w_, s); i; ++i) {
        rhs[i.col()] += a * f[s] * i.value();
        for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator k(w_, s); k; ++k)
          if (i.col() >= k.col())
            normal.valuePtr()[sample_slot_[slot++]] += a2 * i.value() * k.value();
      }
    }
    const int* diag = sample_slot_.data() + sample_begin_.back();
    double peak = 0;
    for (int a = 0; a < h; ++a) peak = std::max(peak, normal.valuePtr()[diag[a]]);
    if (peak == 0) return;
    const double anchor = kRefineAnchor * peak;
    for (int a = 0; a < h; ++a) {
      normal.valuePtr()[diag[a]] += anchor;
      rhs[a] += anchor * q[a];
    }
    solver.factorize(normal);
    if (solver.info() != Eigen::Success) return;
    const Eigen::VectorXd solved = solver.solve(rhs);
    if (solved.minCoeff() >= 0.0) {
      qv = solved;  // the exact minimiser
    } else {
      // Clamping the unconstrained solution can fit worse than Q did (a product of several
      // terms leaves cells barely seen, where Q swings): then coordinate descent on the
      // non-negative problem from the previous Q instead, which can only improve on it.
      const auto objective = [&](const Eigen::VectorXd& x) {
        const Eigen::VectorXd nx = normal.selfadjointView<Eigen::Lower>() * x;
        return x.dot(nx) - 2.0 * rhs.dot(x);
      };
      Eigen::VectorXd x = solved.cwiseMax(0.0);
      if (objective(x) > objective(qv)) {
        x = qv;
        nonnegative_descent(Eigen::SparseMatrix<double>(normal.selfadjointView<Eigen::Lower>()),
                            rhs, x);
      }
      qv = x;
    }
    const Eigen::VectorXd q_io = w_ * qv;
    // Each P_k given Q and the R, then each R_k given Q and the P.
    fit_terms(f, std::span<const double>(q_io.data(), static_cast<std::size_t>(q_io.size())), terms,
              p.first(static_cast<std::size_t>(terms) * m),
              r.first(static_cast<std::size_t>(terms) * v), 1);
  }
}

}  // namespace prt::cmf
