#include "prtlab/sphere/srbf.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "prtlab/base/error.h"

namespace prt {
namespace {

void check_bandwidth(SrbfKernel kernel, double lambda) {
  if (kernel == SrbfKernel::kGaussian) {
    if (!(lambda > 0.0) || !std::isfinite(lambda))
      throw ParameterError(
          fmt::format("Gaussian SRBF: bandwidth {} is not a finite number > 0", lambda));
  } else if (!(lambda > 0.0 && lambda < 1.0)) {
    throw ParameterError(fmt::format("Abel-Poisson SRBF: bandwidth {} is not in (0, 1)", lambda));
  }
}

double abel_poisson(double t, double lambda) {
  const double d = 1.0 - 2.0 * lambda * t + lambda * lambda;
  // d >= (1 - lambda)^2 > 0 for t <= 1; clamp rounding at t = 1.
  const double floor = (1.0 - lambda) * (1.0 - lambda);
  return (1.0 - lambda * lambda) / std::pow(std::max(d, floor), 1.5);
}

// e^(-x) i_l(x) for l = 0 .. lmax by Miller's downward recurrence
// i_(l-1) = i_(l+1) + (2l + 1) / x i_l, normalised with e^(-x) i_0(x) = (1 - e^(-2x)) / (2x).
std::vector<double> scaled_spherical_bessel_i(int lmax, double x) {
  std::vector<double> out(static_cast<std::size_t>(lmax) + 1, 0.0);
  if (x < 1e-8) {
    // i_l(x) ~ x^l / (2l + 1)!!: below double's range for l >= 1 at this x but the first.
    out[0] = 1.0;
    if (lmax >= 1) out[1] = x / 3.0;
    return out;
  }
  const int start = lmax + 20 + static_cast<int>(std::sqrt(40.0 * std::max(x, 1.0)));
  double above = 0.0, cur = 1e-300;
  for (int l = start; l >= 1; --l) {
    const double below = above + (2.0 * l + 1.0) / x * cur;
    above = cur;
    cur = below;
    if (l - 1 <= lmax) out[static_cast<std::size_t>(l - 1)] = cur;
    if (l <= lmax) out[static_cast<std::size_t>(l)] = above;
    if (std::abs(cur) > 1e250) {
      above *= 1e-250;
      cur *= 1e-250;
      for (double& v : out) v *= 1e-250;
    }
  }
  const double i0 = -std::expm1(-2.0 * x) / (2.0 * x);
  const double scale = i0 / out[0];
  for (double& v : out) v *= scale;
  return out;
}

}  // namespace

std::string_view to_string(SrbfKernel k) {
  return k == SrbfKernel::kGaussian ? "gaussian" : "abel_poisson";
}

SrbfKernel srbf_kernel_from(std::string_view name) {
  if (name == "gaussian") return SrbfKernel::kGaussian;
  if (name == "abel_poisson") return SrbfKernel::kAbelPoisson;
  throw ParameterError(fmt::format("SRBF kernel '{}' is none of gaussian, abel_poisson", name));
}

double srbf_eval(SrbfKernel kernel, double t, double lambda) {
  check_bandwidth(kernel, lambda);
  t = std::clamp(t, -1.0, 1.0);
  if (kernel == SrbfKernel::kGaussian) return std::exp(lambda * (t - 1.0));
  return abel_poisson(t, lambda);
}

double srbf_convolution(SrbfKernel kernel, const Vec3d& xi_g, double lambda_g, const Vec3d& xi_h,
                        double lambda_h) {
  check_bandwidth(kernel, lambda_g);
  check_bandwidth(kernel, lambda_h);
  constexpr double kFourPi = 4.0 * kPi;
  if (kernel == SrbfKernel::kAbelPoisson)
    return kFourPi * abel_poisson(glm::dot(xi_g, xi_h), lambda_g * lambda_h);
  const double s = lambda_g + lambda_h;
  const double r = std::min(glm::length(lambda_g * xi_g + lambda_h * xi_h), s);
  if (r < 1e-4) {
    // sinh(r) / r = 1 + r^2 / 6 + r^4 / 120 + ...
    const double r2 = r * r;
    return kFourPi * std::exp(-s) * (1.0 + r2 / 6.0 + r2 * r2 / 120.0);
  }
  return 2.0 * kPi * (std::exp(r - s) - std::exp(-r - s)) / r;
}

double srbf_legendre_coefficient(SrbfKernel kernel, int l, double lambda) {
  check_bandwidth(kernel, lambda);
  if (l < 0) throw ParameterError(fmt::format("SRBF Legendre coefficient: degree {} < 0", l));
  if (kernel == SrbfKernel::kAbelPoisson) return (2.0 * l + 1.0) * std::pow(lambda, l);
  return (2.0 * l + 1.0) * scaled_spherical_bessel_i(l, lambda)[static_cast<std::size_t>(l)];
}

double gaussian_bandwidth_for_sigma(double sigma) {
  if (!(sigma > 0.0) || !std::isfinite(sigma))
    throw ParameterError(fmt::format("SRBF spread sigma {} is not a finite angle > 0", sigma));
  return 1.0 / (sigma * sigma);
}

}  // namespace prt
