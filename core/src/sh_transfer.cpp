#include "prtlab/sh_transfer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>

#include "prtlab/error.h"
#include "prtlab/spherical_harmonics.h"
#include "prtlab/visibility.h"

namespace prt {

namespace {

void check_sh_order(int order) {
  if (order < 1 || order > kMaxShOrder) {
    throw ParameterError(fmt::format("SH transfer order must be in [1, {}], got {}", kMaxShOrder, order));
  }
}

// Rays per GEMM: two 256 x n panels stay in L2 for n up to 100.
constexpr std::size_t kPanel = 256;

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

ShTransfer::MatrixMap ShTransfer::map(std::size_t v) const { return MatrixMap(matrix(v).data(), dim(), dim()); }

void ShTransfer::apply(std::size_t v, std::span<const Vec3d> light, std::span<Vec3d> local) const {
  const int n = dim();
  PRT_CHECK(light.size() == static_cast<std::size_t>(n) && local.size() == static_cast<std::size_t>(n),
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
  weighted_.resize(count * n);
  const auto omega = dirs.solid_angles();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 4096), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t r = range.begin(); r != range.end(); ++r) {
      std::span<double> row(weighted_.data() + r * n, n);
      sh_eval(order_, glm::normalize(dirs.direction(r)), row);
      for (double& y : row) y *= omega[r];
    }
  });
}

void ShTransferIntegrator::integrate(const LocalFrame& frame, std::span<const std::uint32_t> unblocked,
                                     std::span<double> out, Scratch& scratch) const {
  const int n = sh_count(order_);
  PRT_CHECK(out.size() == static_cast<std::size_t>(n) * n, "SH transfer output has {} values, expected {}",
            out.size(), n * n);
  using RowMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  Eigen::Map<RowMat> result(out.data(), n, n);
  result.setZero();
  scratch.local.resize(kPanel * n);
  scratch.global.resize(kPanel * n);

  for (std::size_t base = 0; base < unblocked.size(); base += kPanel) {
    const std::size_t rows = std::min(kPanel, unblocked.size() - base);
    for (std::size_t i = 0; i < rows; ++i) {
      const std::uint32_t r = unblocked[base + i];
      // The float sub-ray direction is the one that was traced; renormalise in double so the
      // local SH see a unit vector.
      const Vec3d d = glm::normalize(dirs_->direction(r));
      sh_eval(order_, frame.to_local(d), std::span<double>(scratch.local.data() + i * n, n));
      std::copy_n(weighted_.data() + static_cast<std::size_t>(r) * n, n, scratch.global.data() + i * n);
    }
    Eigen::Map<const RowMat> a(scratch.local.data(), static_cast<Eigen::Index>(rows), n);
    Eigen::Map<const RowMat> b(scratch.global.data(), static_cast<Eigen::Index>(rows), n);
    result.noalias() += a.transpose() * b;
  }
}

}  // namespace prt
