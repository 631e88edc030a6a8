#include "prtlab/sphere/srbf_projection.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>

#include "prtlab/base/error.h"

namespace prt {
namespace {

void check_basis(const SrbfBasis& b, const char* who) {
  if (b.size() == 0 || b.bandwidths.size() != b.size())
    throw ParameterError(
        fmt::format("{}: an SRBF basis needs centres and one bandwidth each ({} "
                    "centres, {} bandwidths)",
                    who, b.size(), b.bandwidths.size()));
}

}  // namespace

Eigen::MatrixXd srbf_inner_products(const SrbfBasis& a, const SrbfBasis& b) {
  check_basis(a, "srbf_inner_products");
  check_basis(b, "srbf_inner_products");
  if (a.kernel != b.kernel)
    throw ParameterError("srbf_inner_products: the two bases use different kernels");
  const auto rows = static_cast<Eigen::Index>(a.size()), cols = static_cast<Eigen::Index>(b.size());
  Eigen::MatrixXd out(rows, cols);
  tbb::parallel_for(Eigen::Index{0}, rows, [&](Eigen::Index i) {
    for (Eigen::Index j = 0; j < cols; ++j)
      out(i, j) =
          srbf_convolution(a.kernel, a.centres[i], a.bandwidths[i], b.centres[j], b.bandwidths[j]);
  });
  return out;
}

SrbfProjector::SrbfProjector(SrbfBasis basis, const CubemapLayout& layout, double ridge)
    : basis_(std::move(basis)), ridge_(ridge) {
  check_basis(basis_, "SrbfProjector");
  if (!(ridge >= 0) || !std::isfinite(ridge))
    throw ParameterError(fmt::format("SrbfProjector: ridge {} is not a finite number >= 0", ridge));
  Eigen::MatrixXd a = srbf_inner_products(basis_, basis_);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(a, Eigen::EigenvaluesOnly);
  const double lo = eig.eigenvalues().minCoeff(), hi = eig.eigenvalues().maxCoeff();
  gram_condition_ = lo > 0 ? hi / lo : std::numeric_limits<double>::infinity();
  alpha_ = ridge * a.diagonal().maxCoeff();
  a.diagonal().array() += alpha_;
  condition_ =
      lo + alpha_ > 0 ? (hi + alpha_) / (lo + alpha_) : std::numeric_limits<double>::infinity();
  solver_.compute(a);
  if (solver_.info() != Eigen::Success || !std::isfinite(condition_))
    throw ParameterError(fmt::format(
        "SrbfProjector: the Gram system of {} SRBFs is singular (condition number {:.3g}); "
        "raise the ridge",
        basis_.size(), gram_condition_));
  const int n_pixels = layout.pixel_count();
  const auto n = static_cast<Eigen::Index>(basis_.size());
  weights_.resize(n_pixels, n);
  tbb::parallel_for(0, n_pixels, [&](int k) {
    const Vec3d d = layout.direction(k);
    for (Eigen::Index j = 0; j < n; ++j)
      weights_(k, j) =
          srbf_eval(basis_.kernel, glm::dot(d, basis_.centres[j]), basis_.bandwidths[j]) *
          layout.solid_angle(k);
  });
}

Eigen::VectorXd SrbfProjector::project(std::span<const double> pixel_values) const {
  if (static_cast<Eigen::Index>(pixel_values.size()) != weights_.rows())
    throw ParameterError(fmt::format("SrbfProjector: {} pixel values for {} pixels",
                                     pixel_values.size(), weights_.rows()));
  const Eigen::Map<const Eigen::VectorXd> f(pixel_values.data(), weights_.rows());
  return solver_.solve(weights_.transpose() * f);
}

Eigen::MatrixXd SrbfProjector::solve(const Eigen::MatrixXd& b) const {
  if (b.rows() != weights_.cols())
    throw ParameterError(fmt::format("SrbfProjector: right-hand sides of {} values for {} SRBFs",
                                     b.rows(), weights_.cols()));
  return solver_.solve(b);
}

Eigen::VectorXd SrbfProjector::project_sparse(std::span<const std::uint32_t> pixels,
                                              std::span<const double> values) const {
  if (pixels.size() != values.size())
    throw ParameterError("SrbfProjector: as many values as pixels are needed");
  Eigen::VectorXd b = Eigen::VectorXd::Zero(weights_.cols());
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    if (pixels[i] >= weights_.rows())
      throw ParameterError(fmt::format("SrbfProjector: pixel {} out of range", pixels[i]));
    b += values[i] * weights_.row(pixels[i]).transpose();
  }
  return solver_.solve(b);
}

}  // namespace prt
