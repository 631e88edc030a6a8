#include "prtlab/transfer/brdf_weighted_transfer.h"

#include <fmt/format.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "prtlab/base/error.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt {

double CookTorrance::operator()(const Vec3d& l, const Vec3d& v) const {
  const double nl = l.z, nv = v.z;
  if (!(nl > 0) || !(nv > 0)) return 0.0;
  const double pi = std::numbers::pi;
  const Vec3d hs = l + v;
  const double hl = std::sqrt(hs.x * hs.x + hs.y * hs.y + hs.z * hs.z);
  if (!(hl > 0)) return diffuse / pi;
  const Vec3d h = hs / hl;
  const double nh = h.z, vh = v.x * h.x + v.y * h.y + v.z * h.z;
  const double m2 = roughness * roughness, nh2 = nh * nh;
  // Beckmann: exp(-tan^2 / m^2) / (pi m^2 cos^4).
  const double d = std::exp((nh2 - 1.0) / (nh2 * m2)) / (pi * m2 * nh2 * nh2);
  const double f = fresnel0 + (1.0 - fresnel0) * std::pow(1.0 - std::clamp(vh, 0.0, 1.0), 5.0);
  const double g = std::min({1.0, 2.0 * nh * nv / vh, 2.0 * nh * nl / vh});
  return diffuse / pi + (1.0 - diffuse) * d * f * g / (4.0 * nl * nv);
}

void CookTorrance::validate() const {
  const auto bad = [](const char* name, double v, const char* range) {
    return ParameterError(fmt::format("Cook-Torrance BRDF: {} = {} is outside {}", name, v, range));
  };
  if (!(diffuse >= 0 && diffuse <= 1)) throw bad("diffuse (kd)", diffuse, "[0, 1]");
  if (!(roughness > 0 && roughness <= 10)) throw bad("roughness (m)", roughness, "(0, 10]");
  if (!(fresnel0 >= 0 && fresnel0 <= 1)) throw bad("fresnel0 (F0)", fresnel0, "[0, 1]");
}

Eigen::MatrixXd brdf_cosine_kernel(const HemisphereGrid& grid, const CookTorrance& brdf) {
  brdf.validate();
  const int m = grid.cell_count();
  const std::vector<double> projected = grid.projected_solid_angles();
  const double omega = grid.cell_solid_angle();
  Eigen::MatrixXd f(m, m);
  for (int o = 0; o < m; ++o)
    for (int j = 0; j < m; ++j)
      f(o, j) = brdf(grid.direction(j), grid.direction(o)) *
                (projected[static_cast<std::size_t>(j)] / omega);
  return f;
}

double BrdfFold::dropped_fraction() const {
  const double all = singular_values.squaredNorm();
  const double kept = singular_values.head(terms).squaredNorm();
  return all > 0 ? std::max(0.0, all - kept) / all : 0.0;
}

BrdfFold fold_brdf(const HemisphereGrid& grid, const CookTorrance& brdf, int terms) {
  const int m = grid.cell_count();
  if (terms < 1 || terms > m)
    throw ParameterError(
        fmt::format("BRDF fold: {} terms for a grid of {} cells (1 to {})", terms, m, m));
  BrdfFold fold;
  fold.terms = terms;
  fold.view_weight = fold.light_weight = grid.cell_solid_angle();
  const double so = std::sqrt(fold.view_weight), sj = std::sqrt(fold.light_weight);
  const Eigen::MatrixXd a = so * brdf_cosine_kernel(grid, brdf) * sj;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullU | Eigen::ComputeFullV);
  fold.singular_values = svd.singularValues();
  fold.view = svd.matrixU().leftCols(terms) / so;
  fold.light =
      (fold.singular_values.head(terms).asDiagonal() * svd.matrixV().leftCols(terms).transpose()) /
      sj;
  return fold;
}

namespace {

void check_vertex(const TransferMatrix& t, int cells, std::size_t x) {
  if (t.local_count() != cells)
    throw ParameterError(fmt::format("BRDF fold: a transfer of {} local cells for a fold of {}",
                                     t.local_count(), cells));
  if (x >= t.vertex_count())
    throw ParameterError(
        fmt::format("BRDF fold: vertex {} of a transfer of {}", x, t.vertex_count()));
}

}  // namespace

Eigen::MatrixXd folded_vertex(const TransferMatrix& t, const BrdfFold& fold, std::size_t x) {
  check_vertex(t, static_cast<int>(fold.light.cols()), x);
  const int m = t.local_count();
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(fold.terms, static_cast<Eigen::Index>(t.cols()));
  for (int j = 0; j < m; ++j) {
    const std::size_t row = x * static_cast<std::size_t>(m) + static_cast<std::size_t>(j);
    for (std::uint32_t e = t.row_offsets()[row]; e < t.row_offsets()[row + 1]; ++e)
      out.col(t.column(e)) += static_cast<double>(t.value(e)) * fold.light.col(j);
  }
  return out;
}

Eigen::MatrixXd brdf_weighted_vertex(const TransferMatrix& t, const Eigen::MatrixXd& kernel,
                                     std::size_t x) {
  check_vertex(t, static_cast<int>(kernel.cols()), x);
  const int m = t.local_count();
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(kernel.rows(), static_cast<Eigen::Index>(t.cols()));
  for (int j = 0; j < m; ++j) {
    const std::size_t row = x * static_cast<std::size_t>(m) + static_cast<std::size_t>(j);
    for (std::uint32_t e = t.row_offsets()[row]; e < t.row_offsets()[row + 1]; ++e)
      for (Eigen::Index o = 0; o < kernel.rows(); ++o)
        out(o, t.column(e)) += kernel(o, j) * static_cast<double>(t.value(e));
  }
  return out;
}

double folded_squared_norm(const TransferMatrix& t, const BrdfFold& fold) {
  const int m = t.local_count();
  if (fold.light.cols() != m)
    throw ParameterError(fmt::format("BRDF fold: a transfer of {} local cells for a fold of {}", m,
                                     fold.light.cols()));
  const Eigen::VectorXd col = fold.light.colwise().squaredNorm().transpose();
  double s = 0;
  for (std::size_t row = 0; row < t.rows(); ++row) {
    const double w = col(static_cast<Eigen::Index>(row % static_cast<std::size_t>(m)));
    for (std::uint32_t e = t.row_offsets()[row]; e < t.row_offsets()[row + 1]; ++e)
      s += static_cast<double>(t.value(e)) * t.value(e) * w;
  }
  return s;
}

}  // namespace prt
