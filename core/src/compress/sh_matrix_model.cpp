#include "prtlab/compress/sh_matrix_model.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Core>
#include <cmath>

#include "prtlab/base/error.h"
#include "prtlab/sphere/spherical_harmonics.h"
#include "prtlab/transfer/radiance_to_bins.h"

namespace prt {
namespace {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using ConstMap = Eigen::Map<const RowMatrix>;

void check_order(int order, const char* what) {
  if (order < 1 || order > kMaxShOrder)
    throw ParameterError(
        fmt::format("SH matrix model: {} order {} is not in 1..{}", what, order, kMaxShOrder));
}

// Vertices per task: a fixed partition, so that the double sums do not depend on the threads.
constexpr std::size_t kChunk = 64;

}  // namespace

ShMatrixModel::ShMatrixModel(const CubemapLayout& cubemap, const HemisphereGrid& grid,
                             int light_order, int output_order)
    : resolution_(cubemap.resolution()), cells_(grid.cell_count()) {
  check_order(light_order, "light");
  check_order(output_order, "output");
  n_light_ = sh_count(light_order);
  n_out_ = sh_count(output_order);
  const int n = cubemap.pixel_count();
  y_.assign(static_cast<std::size_t>(n) * n_light_, 0.0);
  const auto dirs = cubemap.directions();
  for (int q = 0; q < n; ++q)
    sh_eval(light_order, dirs[q],
            std::span<double>(&y_[static_cast<std::size_t>(q) * n_light_], n_light_));
  b_ = sh_cell_integrals(grid, output_order);
  const ConstMap y(y_.data(), n, n_light_), b(b_.data(), cells_, n_out_);
  const RowMatrix gb = b.transpose() * b, gy = y.transpose() * y;
  gb_.assign(gb.data(), gb.data() + gb.size());
  gy_.assign(gy.data(), gy.data() + gy.size());
}

double ShMatrixModel::relative_frobenius_error(const TransferMatrix& t,
                                               const MatrixOf& matrix) const {
  PRT_CHECK(t.local_count() == cells_ && t.cols() == y_.size() / n_light_,
            "SH matrix model of M = {}, N = {} for a transfer of M = {}, N = {}", cells_,
            y_.size() / n_light_, t.local_count(), t.cols());
  const std::size_t vertices = t.vertex_count();
  const ConstMap b(b_.data(), cells_, n_out_), gb(gb_.data(), n_out_, n_out_),
      gy(gy_.data(), n_light_, n_light_);
  const std::size_t chunks = (vertices + kChunk - 1) / kChunk;
  std::vector<double> partial(chunks, 0.0);
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
    std::vector<double> xs(static_cast<std::size_t>(n_out_) * n_light_);
    RowMatrix z(cells_, n_light_);
    double acc = 0;
    for (std::size_t v = c * kChunk; v < std::min(vertices, (c + 1) * kChunk); ++v) {
      matrix(v, xs);
      const ConstMap x(xs.data(), n_out_, n_light_);
      acc += ((gb * x).array() * (x * gy).array()).sum();
      // Z_p[j, k] = sum_q T_p[j, q] y_k(d_q): the cross term is sum(B .* (Z_p X^T)).
      z.setZero();
      for (int j = 0; j < cells_; ++j) {
        const std::size_t row = v * static_cast<std::size_t>(cells_) + static_cast<std::size_t>(j);
        for (std::uint32_t e = t.row_offsets()[row]; e < t.row_offsets()[row + 1]; ++e) {
          const double value = t.counts()[e] * t.scale();
          const double* yq = &y_[static_cast<std::size_t>(t.column(e)) * n_light_];
          for (int k = 0; k < n_light_; ++k) z(j, k) += value * yq[k];
          acc += value * value;
        }
      }
      acc -= 2.0 * (b.array() * (z * x.transpose()).array()).sum();
    }
    partial[c] = acc;
  });
  double diff = 0;
  for (double p : partial) diff += p;
  double norm = 0;
  for (std::size_t e = 0; e < t.nnz(); ++e) norm += std::pow(t.counts()[e] * t.scale(), 2);
  diff = std::max(diff, 0.0);
  return norm > 0 ? std::sqrt(diff / norm) : std::sqrt(diff);
}

ModelRadiance ShMatrixModel::radiance(const Cubemap& radiance, std::size_t vertices,
                                      const MatrixOf& matrix, const MatrixOf& magnitude_of) const {
  if (radiance.layout.resolution() != resolution_)
    throw ParameterError(fmt::format("SH matrix model of cubemap resolution {}: a light of {}",
                                     resolution_, radiance.layout.resolution()));
  const int n = radiance.layout.pixel_count();
  const auto omega = radiance.layout.solid_angles();
  // l = Y L and |Y| |L|, per channel.
  RowMatrix l = RowMatrix::Zero(n_light_, 3), la = RowMatrix::Zero(n_light_, 3);
  for (int q = 0; q < n; ++q) {
    const Vec3d lq = Vec3d(radiance.radiance[static_cast<std::size_t>(q)]) * omega[q];
    const double* yq = &y_[static_cast<std::size_t>(q) * n_light_];
    for (int k = 0; k < n_light_; ++k)
      for (int ch = 0; ch < 3; ++ch) {
        l(k, ch) += yq[k] * lq[ch];
        la(k, ch) += std::abs(yq[k]) * std::abs(lq[ch]);
      }
  }
  const ConstMap b(b_.data(), cells_, n_out_);
  const RowMatrix babs = b.cwiseAbs();
  ModelRadiance out;
  out.values.assign(vertices * static_cast<std::size_t>(cells_), Vec3d(0.0));
  out.magnitude.assign(out.values.size(), Vec3d(0.0));
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertices, kChunk), [&](const auto& r) {
    std::vector<double> xs(static_cast<std::size_t>(n_out_) * n_light_), xa(xs.size());
    for (std::size_t v = r.begin(); v != r.end(); ++v) {
      matrix(v, xs);
      magnitude_of(v, xa);
      const RowMatrix value = b * (ConstMap(xs.data(), n_out_, n_light_) * l);
      const RowMatrix size = babs * (ConstMap(xa.data(), n_out_, n_light_) * la);
      for (int j = 0; j < cells_; ++j) {
        const std::size_t row = v * static_cast<std::size_t>(cells_) + static_cast<std::size_t>(j);
        out.values[row] = Vec3d(value(j, 0), value(j, 1), value(j, 2));
        out.magnitude[row] = Vec3d(size(j, 0), size(j, 1), size(j, 2));
      }
    }
  });
  return out;
}

}  // namespace prt
