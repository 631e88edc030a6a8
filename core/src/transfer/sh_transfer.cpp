#include "prtlab/transfer/sh_transfer.h"

#include <tbb/parallel_for.h>

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>

#include "prtlab/base/error.h"
#include "prtlab/sphere/spherical_harmonics.h"
#include "prtlab/transfer/visibility.h"

namespace prt {

namespace {

void check_sh_order(int order) {
  if (order < 1 || order > kMaxShOrder) {
    throw ParameterError(
        fmt::format("SH transfer order must be in [1, {}], got {}", kMaxShOrder, order));
  }
}

// Rays per rank-k update: a 256 x n panel stays in L2 for n up to 100.
constexpr std::size_t kPanel = 256;

using RowMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

}  // namespace

ShTransfer::ShTransfer(int order, std::size_t vertices) : order_(order), vertices_(vertices) {
  check_sh_order(order);
  data_.assign(vertices * static_cast<std::size_t>(dim()) * dim(), 0.0);
}

std::span<const double> ShTransfer::matrix(std::size_t v) const {
  PRT_CHECK(v < vertices_, "SH transfer vertex {} out of range ({})", v, vertices_);
  const std::size_t nn = static_cast<std::size_t>(dim()) * dim();
  return std::span<const double>(data_).subspan(v * nn, nn);
}

std::span<double> ShTransfer::mutable_matrix(std::size_t v) {
  PRT_CHECK(v < vertices_, "SH transfer vertex {} out of range ({})", v, vertices_);
  const std::size_t nn = static_cast<std::size_t>(dim()) * dim();
  return std::span<double>(data_).subspan(v * nn, nn);
}

ShTransfer::MatrixMap ShTransfer::map(std::size_t v) const {
  return MatrixMap(matrix(v).data(), dim(), dim());
}

void ShTransfer::apply(std::size_t v, std::span<const Vec3d> light, std::span<Vec3d> local) const {
  const int n = dim();
  PRT_CHECK(
      light.size() == static_cast<std::size_t>(n) && local.size() == static_cast<std::size_t>(n),
      "SH transfer apply: light has {} and output {} coefficients, order {} needs {}", light.size(),
      local.size(), order_, n);
  const auto m = matrix(v);
  for (int i = 0; i < n; ++i) {
    Vec3d acc{0.0};
    for (int k = 0; k < n; ++k) acc += m[static_cast<std::size_t>(i) * n + k] * light[k];
    local[i] = acc;
  }
}

ShTransferIntegrator::ShTransferIntegrator(const SupersampledCubemap& dirs, int order)
    : dirs_(&dirs), order_(order) {
  check_sh_order(order);
  const std::size_t n = static_cast<std::size_t>(sh_count(order));
  const std::size_t count = dirs.subray_count();
  table_.resize(count * n);
  const auto omega = dirs.solid_angles();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 4096),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t r = range.begin(); r != range.end(); ++r) {
                        std::span<double> row(table_.data() + r * n, n);
                        // The float sub-ray direction is the one traced; renormalise in double.
                        sh_eval(order_, glm::normalize(dirs.direction(r)), row);
                        const double w = std::sqrt(omega[r]);
                        for (double& y : row) y *= w;
                      }
                    });

  // Fibonacci-sphere directions: well spread, so [y(samples)] has full column rank with a
  // small condition number for every order up to 10.
  const std::size_t p = 2 * n + 16;
  samples_.resize(p);
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (std::size_t i = 0; i < p; ++i) {
    const double z = 1.0 - (2.0 * static_cast<double>(i) + 1.0) / static_cast<double>(p);
    const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden * static_cast<double>(i);
    samples_[i] = {rho * std::cos(phi), rho * std::sin(phi), z};
  }
  RowMat y(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < p; ++i)
    sh_eval(order_, samples_[i], std::span<double>(y.data() + i * n, n));
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(y, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& sv = svd.singularValues();
  PRT_CHECK(sv(sv.size() - 1) > 1e-6 * sv(0), "SH sample directions are degenerate (order {})",
            order);
  const Eigen::MatrixXd pinv =
      svd.matrixV() * sv.cwiseInverse().asDiagonal() * svd.matrixU().transpose();  // n x P
  pinv_.resize(n * p);
  Eigen::Map<RowMat>(pinv_.data(), static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(p)) =
      pinv;
}

void ShTransferIntegrator::rotation(const LocalFrame& frame, std::span<double> out,
                                    Scratch& scratch) const {
  const auto n = static_cast<Eigen::Index>(sh_count(order_));
  const auto p = static_cast<Eigen::Index>(samples_.size());
  PRT_CHECK(out.size() == static_cast<std::size_t>(n * n),
            "SH rotation output has {} values, expected {}", out.size(), n * n);
  scratch.local.resize(static_cast<std::size_t>(p * n));
  for (Eigen::Index i = 0; i < p; ++i)
    sh_eval(order_, frame.to_local(samples_[i]),
            std::span<double>(scratch.local.data() + i * n, static_cast<std::size_t>(n)));
  // [y(F^T s_i)] = [y(s_i)] R^T  =>  R^T = pinv [y(F^T s_i)].
  const Eigen::Map<const RowMat> yl(scratch.local.data(), p, n);
  const Eigen::Map<const RowMat> pinv(pinv_.data(), n, p);
  Eigen::Map<RowMat>(out.data(), n, n).noalias() = (pinv * yl).transpose();
}

void ShTransferIntegrator::integrate(const LocalFrame& frame,
                                     std::span<const std::uint32_t> unblocked,
                                     std::span<double> out, Scratch& scratch) const {
  const auto n = static_cast<Eigen::Index>(sh_count(order_));
  const std::size_t nn = static_cast<std::size_t>(n);
  PRT_CHECK(out.size() == nn * nn, "SH transfer output has {} values, expected {}", out.size(),
            nn * nn);
  scratch.panel.resize(kPanel * nn);
  scratch.gram.assign(nn * nn, 0.0);
  scratch.rotation.resize(nn * nn);
  // Column-major n x n: the lower triangle receives the rank-k updates.
  Eigen::Map<Eigen::MatrixXd> gram(scratch.gram.data(), n, n);
  for (std::size_t base = 0; base < unblocked.size(); base += kPanel) {
    const std::size_t rows = std::min(kPanel, unblocked.size() - base);
    for (std::size_t i = 0; i < rows; ++i)
      std::copy_n(table_.data() + static_cast<std::size_t>(unblocked[base + i]) * nn, nn,
                  scratch.panel.data() + i * nn);
    const Eigen::Map<const RowMat> b(scratch.panel.data(), static_cast<Eigen::Index>(rows), n);
    gram.selfadjointView<Eigen::Lower>().rankUpdate(b.transpose());
  }
  rotation(frame, scratch.rotation, scratch);
  const Eigen::Map<const RowMat> rot(scratch.rotation.data(), n, n);
  Eigen::Map<RowMat>(out.data(), n, n).noalias() =
      rot * gram.selfadjointView<Eigen::Lower>().toDenseMatrix();
}

}  // namespace prt
