#include "prtlab/lighting/srbf_light.h"

#include <LBFGSB.h>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "prtlab/base/error.h"
#include "prtlab/base/relative_error.h"
#include "prtlab/sphere/icosphere.h"

namespace prt {
namespace {

double luminance(const Vec3d& c) {
  return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
}

Vec3d from_angles(double theta, double phi) {
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

void to_angles(const Vec3d& d, double& theta, double& phi) {
  theta = std::acos(std::clamp(d.z, -1.0, 1.0));
  phi = std::atan2(d.y, d.x);
}

void check_light(const Cubemap& light) {
  for (const Rgb& c : light.radiance)
    if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z))
      throw ParameterError("SRBF fit: the light has a non-finite radiance value");
}

// The light's pixels as the fits read them: directions, weights and radiance in double.
struct Samples {
  std::span<const Vec3d> dirs;
  std::span<const double> omega;
  std::vector<Vec3d> value;
  double norm2 = 0;  ///< sum Omega_k |L_k|^2
  explicit Samples(const Cubemap& light)
      : dirs(light.layout.directions()), omega(light.layout.solid_angles()) {
    value.reserve(light.radiance.size());
    for (std::size_t k = 0; k < light.radiance.size(); ++k) {
      value.emplace_back(light.radiance[k]);
      norm2 += omega[k] * glm::dot(value.back(), value.back());
    }
  }
  std::size_t size() const { return value.size(); }
};

// Phi (pixels x centres, row-major) and the residuals R_k = L_k - sum_j c_j Phi_kj; returns E.
double residuals(const SrbfLight& fit, const Samples& s, std::vector<double>& phi,
                 std::vector<Vec3d>& r) {
  const std::size_t n = fit.count(), m = s.size();
  phi.resize(m * n);
  r.resize(m);
  tbb::parallel_for(std::size_t{0}, m, [&](std::size_t k) {
    Vec3d acc = s.value[k];
    double* row = phi.data() + k * n;
    for (std::size_t j = 0; j < n; ++j) {
      row[j] = srbf_eval(fit.kernel, glm::dot(s.dirs[k], fit.centres[j]), fit.bandwidths[j]);
      acc -= row[j] * fit.coefficients[j];
    }
    r[k] = acc;
  });
  double e = 0;
  for (std::size_t k = 0; k < m; ++k) e += s.omega[k] * glm::dot(r[k], r[k]);
  return e;
}

// L-BFGS-B objective over one parameter block (centres as angles, or log bandwidths) with the
// rest fixed; E scaled by 1 / sum Omega L^2 so its size is the squared relative error.
struct BlockObjective {
  enum class Block { kCentres, kBandwidths };
  SrbfLight& fit;
  const Samples& s;
  Block block;
  std::vector<double> phi;
  std::vector<Vec3d> r;

  void unpack(const Eigen::VectorXd& x) {
    const std::size_t n = fit.count();
    for (std::size_t j = 0; j < n; ++j) {
      if (block == Block::kCentres)
        fit.centres[j] = from_angles(x[2 * j], x[2 * j + 1]);
      else
        fit.bandwidths[j] = std::exp(x[j]);
    }
  }

  double operator()(const Eigen::VectorXd& x, Eigen::VectorXd& grad) {
    unpack(x);
    const double e = residuals(fit, s, phi, r);
    const std::size_t n = fit.count(), m = s.size();
    const double scale = 1.0 / s.norm2;
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t j) {
      const double lambda = fit.bandwidths[j];
      Vec3d gxi(0.0);
      double glambda = 0;
      for (std::size_t k = 0; k < m; ++k) {
        const double g = phi[k * n + j];
        if (g == 0.0) continue;
        const double w = -2.0 * s.omega[k] * glm::dot(r[k], fit.coefficients[j]) * g;
        if (block == Block::kCentres)
          gxi += w * lambda * s.dirs[k];
        else
          glambda += w * (glm::dot(s.dirs[k], fit.centres[j]) - 1.0) * lambda;  // d/d log lambda
      }
      if (block == Block::kCentres) {
        const double theta = x[2 * j], ph = x[2 * j + 1];
        const Vec3d dtheta{std::cos(theta) * std::cos(ph), std::cos(theta) * std::sin(ph),
                           -std::sin(theta)};
        const Vec3d dphi{-std::sin(theta) * std::sin(ph), std::sin(theta) * std::cos(ph), 0.0};
        grad[2 * j] = scale * glm::dot(gxi, dtheta);
        grad[2 * j + 1] = scale * glm::dot(gxi, dphi);
      } else {
        grad[j] = scale * glambda;
      }
    });
    return e * scale;
  }
};

// One L-BFGS-B step on a block; keeps the best point seen when the line search gives up.
bool optimise_block(SrbfLight& fit, const Samples& s, BlockObjective::Block block,
                    const ScatteredFitOptions& o) {
  const std::size_t n = fit.count();
  const bool centres = block == BlockObjective::Block::kCentres;
  Eigen::VectorXd x(centres ? 2 * n : n), lb(x.size()), ub(x.size());
  for (std::size_t j = 0; j < n; ++j) {
    if (centres) {
      double theta, phi;
      to_angles(fit.centres[j], theta, phi);
      // A centre at a pole has no phi direction; nudge it so the gradient is defined.
      theta = std::clamp(theta, 1e-6, kPi - 1e-6);
      x[2 * j] = theta;
      x[2 * j + 1] = phi;
      lb[2 * j] = -kPi;  // theta may cross a pole: the angles stay a valid parameterisation
      ub[2 * j] = 2 * kPi;
      lb[2 * j + 1] = -4 * kPi;
      ub[2 * j + 1] = 4 * kPi;
    } else {
      x[j] = std::log(std::clamp(fit.bandwidths[j], o.min_bandwidth, o.max_bandwidth));
      lb[j] = std::log(o.min_bandwidth);
      ub[j] = std::log(o.max_bandwidth);
    }
  }
  LBFGSpp::LBFGSBParam<double> param;
  param.max_iterations = o.lbfgs_iterations;
  param.epsilon = 1e-7;
  param.max_linesearch = 40;
  LBFGSpp::LBFGSBSolver<double> solver(param);
  BlockObjective f{fit, s, block, {}, {}};
  const SrbfLight before = fit;
  Eigen::VectorXd g0(x.size());
  const double e0 = f(x, g0);
  double fx = e0;
  bool ok = true;
  try {
    solver.minimize(f, x, fx, lb, ub);
    f.unpack(x);
  } catch (const std::runtime_error&) {
    // LBFGSpp throws when a line search fails; the objective's last evaluation may be worse
    // than the start, so fall back to the start unless the solver's x improved.
    ok = false;
    Eigen::VectorXd g(x.size());
    fx = f(x, g);
  }
  if (!(fx <= e0)) fit = before;
  return ok;
}

// Heuristic initial centres (section 5.3): each sample direction's coverage, the geodesic radius
// of the cone of nearest directions that still resemble it; centres by coverage-weighted
// luminance, each marking its cone taken.
void initial_centres(SrbfLight& fit, const Cubemap& light, const ScatteredFitOptions& o) {
  const CubemapLayout coarse(std::min(light.layout.resolution(), 32));
  const int m = coarse.pixel_count();
  std::vector<double> y(static_cast<std::size_t>(m));
  double mean_sq = 0;
  for (int k = 0; k < m; ++k) {
    y[k] = luminance(Vec3d(light.radiance[light.layout.pixel_of(coarse.direction(k))]));
    mean_sq += y[k] * y[k] / m;
  }
  // Resemblance is relative to the direction's own luminance: the cone of a Gaussian lobe's peak
  // then ends where the lobe has fallen to 1 - sqrt(threshold) of it, at a fixed multiple of its
  // sigma (kConeToSigma), whatever its brightness.
  const auto threshold_of = [&](int j) {
    return o.coverage_threshold * y[j] * y[j] + 1e-12 * std::max(mean_sq, 1e-300);
  };
  const double cone_to_sigma = std::sqrt(-2.0 * std::log(1.0 - std::sqrt(o.coverage_threshold)));
  std::vector<double> coverage(static_cast<std::size_t>(m));
  const double floor = 0.5 * std::sqrt(4 * kPi / m);
  tbb::parallel_for(0, m, [&](int j) {
    std::vector<std::pair<double, int>> near;
    near.reserve(static_cast<std::size_t>(m));
    for (int k = 0; k < m; ++k)
      if (k != j) near.emplace_back(-glm::dot(coarse.direction(j), coarse.direction(k)), k);
    std::sort(near.begin(), near.end());
    int differing = 0;
    double radius = floor;
    for (std::size_t i = 0; i < near.size(); ++i) {
      const int k = near[i].second;
      if ((y[j] - y[k]) * (y[j] - y[k]) > threshold_of(j)) ++differing;
      if (i >= 4 && differing > o.coverage_ratio * static_cast<double>(i + 1)) break;
      radius = std::acos(std::clamp(-near[i].first, -1.0, 1.0));
    }
    coverage[static_cast<std::size_t>(j)] = std::clamp(radius / cone_to_sigma, floor, kPi / 2);
  });
  std::vector<int> picked;
  std::vector<double> sigma_of;
  if (o.seeding == SrbfSeeding::kResidual) {
    // Greedy on the residual: the next centre where coverage x |residual luminance| is largest,
    // its coefficient the residual there; the residual then loses that SRBF.
    std::vector<double> res = y;
    for (int i = 0; i < o.count; ++i) {
      int best = 0;
      double best_score = -1;
      for (int k = 0; k < m; ++k) {
        const double score = std::abs(res[k]) * coverage[k];
        if (score > best_score) best_score = score, best = k;
      }
      const double sigma = coverage[best];
      const double lambda = std::clamp(1.0 / (sigma * sigma), o.min_bandwidth, o.max_bandwidth);
      const double amp = res[best];
      for (int k = 0; k < m; ++k)
        res[k] -=
            amp * std::exp(lambda * (glm::dot(coarse.direction(best), coarse.direction(k)) - 1));
      picked.push_back(best);
      sigma_of.push_back(sigma);
    }
  } else {
    std::vector<int> order(static_cast<std::size_t>(m));
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) {
      const double pa = y[a] * coverage[a], pb = y[b] * coverage[b];
      return pa != pb ? pa > pb : a < b;
    });
    double shrink = 1.0;
    const auto covers = [&](int p, int k) {
      return glm::dot(coarse.direction(p), coarse.direction(k)) >= std::cos(shrink * coverage[p]);
    };
    while (static_cast<int>(picked.size()) < o.count && shrink >= 1e-3) {
      std::vector<char> marked(static_cast<std::size_t>(m), 0);
      for (int p : picked)
        for (int k = 0; k < m; ++k)
          if (k == p || covers(p, k)) marked[k] = 1;
      bool added = false;
      for (int k : order) {
        if (static_cast<int>(picked.size()) >= o.count) break;
        if (marked[k]) continue;
        picked.push_back(k);
        added = true;
        for (int q = 0; q < m; ++q)
          if (q == k || covers(k, q)) marked[q] = 1;
      }
      if (!added) shrink *= 0.5;
    }
    for (std::size_t i = 0; static_cast<int>(picked.size()) < o.count; ++i)
      picked.push_back(order[i % order.size()]);
    for (int p : picked) sigma_of.push_back(shrink * coverage[p]);
  }
  fit.centres.clear();
  fit.bandwidths.clear();
  std::vector<int> seen;
  for (std::size_t i = 0; i < picked.size(); ++i) {
    Vec3d d = coarse.direction(picked[i]);
    // A direction picked twice is nudged apart (the optimiser moves them).
    const auto repeats = std::count(seen.begin(), seen.end(), picked[i]);
    if (repeats > 0)
      d = glm::normalize(d + 2e-2 * static_cast<double>(repeats) * from_angles(1.0 + i, 2.0 * i));
    seen.push_back(picked[i]);
    fit.centres.push_back(d);
    const double sigma = sigma_of[i];
    fit.bandwidths.push_back(std::clamp(1.0 / (sigma * sigma), o.min_bandwidth, o.max_bandwidth));
  }
}

double spacing_642() {
  static const double d = min_geodesic_distance(icosphere_vertices(3));
  return d;
}

}  // namespace

Vec3d SrbfLight::evaluate(const Vec3d& d) const {
  Vec3d acc(0.0);
  for (std::size_t j = 0; j < count(); ++j)
    acc += coefficients[j] * srbf_eval(kernel, glm::dot(d, centres[j]), bandwidths[j]);
  return acc;
}

Cubemap SrbfLight::to_cubemap(int resolution) const {
  Cubemap out(resolution);
  tbb::parallel_for(0, out.layout.pixel_count(), [&](int k) {
    out.radiance[static_cast<std::size_t>(k)] = Rgb(evaluate(out.layout.direction(k)));
  });
  return out;
}

std::vector<Vec3d> uniform_sphere_points(int count) {
  if (count < 1) throw ParameterError(fmt::format("uniform SRBF centres: count {} < 1", count));
  for (int level = 0; level <= kMaxIcosphereLevel; ++level)
    if (icosphere_vertex_count(level) == count) return icosphere_vertices(level);
  std::vector<Vec3d> out;
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / count;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    out.push_back({r * std::cos(golden * i), r * std::sin(golden * i), z});
  }
  return out;
}

double uniform_gaussian_spread_per_spacing() {
  return (kPi / 40.0) / spacing_642();
}

double uniform_gaussian_bandwidth(std::span<const Vec3d> centres) {
  const double sigma = uniform_gaussian_spread_per_spacing() * min_geodesic_distance(centres);
  return gaussian_bandwidth_for_sigma(sigma);
}

double srbf_relative_error(const SrbfLight& fit, const Cubemap& light) {
  const Samples s(light);
  std::vector<double> phi;
  std::vector<Vec3d> r;
  const double e = residuals(fit, s, phi, r);
  return relative_to(std::sqrt(e), std::sqrt(s.norm2), "relative error of an SRBF light fit");
}

double fit_srbf_coefficients(SrbfLight& fit, const Cubemap& light, double ridge) {
  check_light(light);
  if (fit.count() == 0 || fit.bandwidths.size() != fit.count())
    throw ParameterError("SRBF fit: no centres, or not one bandwidth per centre");
  const Samples s(light);
  const auto n = static_cast<Eigen::Index>(fit.count());
  const auto m = static_cast<Eigen::Index>(s.size());
  Eigen::MatrixXd phi(m, n);
  tbb::parallel_for(Eigen::Index{0}, m, [&](Eigen::Index k) {
    for (Eigen::Index j = 0; j < n; ++j)
      phi(k, j) = srbf_eval(fit.kernel, glm::dot(s.dirs[k], fit.centres[j]), fit.bandwidths[j]) *
                  std::sqrt(s.omega[k]);
  });
  Eigen::MatrixXd rhs(m, 3);
  for (Eigen::Index k = 0; k < m; ++k)
    for (int c = 0; c < 3; ++c) rhs(k, c) = s.value[k][c] * std::sqrt(s.omega[k]);
  Eigen::MatrixXd a = phi.transpose() * phi;
  const double top = a.diagonal().maxCoeff();
  a.diagonal().array() += ridge * top;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(a);
  if (ldlt.info() != Eigen::Success)
    throw ParameterError("SRBF fit: the normal equations could not be factored");
  const Eigen::MatrixXd c = ldlt.solve(phi.transpose() * rhs);
  fit.coefficients.assign(fit.count(), Vec3d(0.0));
  for (Eigen::Index j = 0; j < n; ++j) fit.coefficients[j] = {c(j, 0), c(j, 1), c(j, 2)};
  const auto d = ldlt.vectorD().cwiseAbs();
  return d.minCoeff() > 0 ? d.maxCoeff() / d.minCoeff() : std::numeric_limits<double>::infinity();
}

SrbfLight fit_uniform_srbf(const Cubemap& light, int count, double ridge) {
  SrbfLight fit;
  fit.centres = uniform_sphere_points(count);
  const double lambda = count >= 2 ? uniform_gaussian_bandwidth(fit.centres) : 1.0;
  fit.bandwidths.assign(fit.centres.size(), lambda);
  fit_srbf_coefficients(fit, light, ridge);
  return fit;
}

SrbfLight fit_scattered_srbf(const Cubemap& light, const ScatteredFitOptions& o,
                             ScatteredFitReport* report) {
  check_light(light);
  if (o.count < 1 || o.rounds < 0 || o.lbfgs_iterations < 1 || !(o.min_bandwidth > 0) ||
      !(o.max_bandwidth > o.min_bandwidth) ||
      !(o.coverage_threshold > 0 && o.coverage_threshold < 1) ||
      !(o.coverage_ratio > 0 && o.coverage_ratio <= 1))
    throw ParameterError(fmt::format(
        "scattered SRBF fit: count {} and rounds {} must be positive, bandwidth bounds {} < {}, "
        "coverage threshold {} in (0, 1), ratio {} in (0, 1]",
        o.count, o.rounds, o.min_bandwidth, o.max_bandwidth, o.coverage_threshold,
        o.coverage_ratio));
  SrbfLight fit;
  fit.scattered = true;
  initial_centres(fit, light, o);
  fit_srbf_coefficients(fit, light, o.ridge);
  const Samples s(light);
  ScatteredFitReport rep;
  if (!(s.norm2 > 0)) {
    // A black light: the zero coefficients reproduce it exactly (a backend projecting a black
    // light gets the zero light), but its relative error is 0 / 0, undefined rather than a
    // perfect score, and the optimiser's scaled objective would divide by it.
    rep.initial_error = rep.error = srbf_relative_error(fit, light);
    if (report) *report = rep;
    return fit;
  }
  double error = srbf_relative_error(fit, light);
  rep.initial_error = error;
  for (int round = 1; round <= o.rounds; ++round) {
    if (!optimise_block(fit, s, BlockObjective::Block::kCentres, o)) ++rep.lbfgs_failures;
    if (!optimise_block(fit, s, BlockObjective::Block::kBandwidths, o)) ++rep.lbfgs_failures;
    const SrbfLight kept = fit;
    fit_srbf_coefficients(fit, light, o.ridge);
    double next = srbf_relative_error(fit, light);
    if (next > error) {  // the ridge can make the solve a little worse than the blocks' point
      fit = kept;
      next = srbf_relative_error(fit, light);
    }
    rep.rounds = round;
    if (o.on_round) o.on_round(round, next);
    const bool converged = error * error - next * next < o.tolerance * error * error;
    error = std::min(error, next);
    if (converged) break;
  }
  rep.error = error;
  if (report) *report = rep;
  return fit;
}

}  // namespace prt
