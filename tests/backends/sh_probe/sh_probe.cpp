#include "sh_probe/sh_probe.h"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <cmath>

#include "prtlab/base/error.h"
#include "prtlab/sphere/spherical_harmonics.h"
#include "prtlab/storage/archive.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/transfer/radiance_to_bins.h"

namespace prt::sh_probe {
namespace {

int grid_side(int m) {
  return static_cast<int>(std::lround(std::sqrt(static_cast<double>(m))));
}

class ShProbeCompressor final : public Compressor {
 public:
  explicit ShProbeCompressor(int order) : order_(order) {}
  std::unique_ptr<CompressedTransfer> compress(const TransferInput& input,
                                               Progress& progress) const override {
    check_transfer_shape(input, kName);
    auto out = std::make_unique<ShProbeTransfer>(input.transfer, order_);
    progress.finish();
    return out;
  }

 private:
  int order_;
};

}  // namespace

ShProbeTransfer::ShProbeTransfer(TransferMatrix t, int order) : t_(std::move(t)), order_(order) {
  const int m = t_.local_count(), n = sh_count(order);
  const HemisphereGrid grid(grid_side(m));
  if (grid.cell_count() != m)
    throw ParameterError(fmt::format("{}: M = {} is no square grid", kName, m));
  const std::vector<double> b = sh_cell_integrals(grid, order);
  const Eigen::MatrixXd bm =
      Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
          b.data(), m, n);
  const Eigen::MatrixXd pinv = bm.completeOrthogonalDecomposition().pseudoInverse();  // n x M
  p_.resize(static_cast<std::size_t>(n) * m);
  Eigen::MatrixXd pf(n, m);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      p_[static_cast<std::size_t>(i) * m + j] = static_cast<float>(pinv(i, j));
      pf(i, j) = p_[static_cast<std::size_t>(i) * m + j];
    }
  // A column of a vertex block has one entry v in some row j, so its residual is v (I - B P) e_j:
  // the squared error is sum over entries of v^2 q_j, q_j = ||(I - B P) e_j||^2.
  const Eigen::MatrixXd residual = Eigen::MatrixXd::Identity(m, m) - bm * pf;
  std::vector<double> q(static_cast<std::size_t>(m));
  for (int j = 0; j < m; ++j) q[static_cast<std::size_t>(j)] = residual.col(j).squaredNorm();
  double err = 0, norm = 0;
  const auto offsets = t_.row_offsets();
  for (std::size_t r = 0; r < t_.rows(); ++r)
    for (auto i = offsets[r]; i < offsets[r + 1]; ++i) {
      const double v = t_.value(i);
      norm += v * v;
      err += v * v * q[r % static_cast<std::size_t>(m)];
    }
  expected_ = norm > 0 ? std::sqrt(err / norm) : 0.0;
}

StorageReport ShProbeTransfer::storage() const {
  return {{{"row_offsets", (t_.rows() + 1) * std::uint64_t{4}, "u32 per row + 1 (CSR of T)"},
           {"columns", t_.nnz() * std::uint64_t{t_.narrow_columns() ? 2u : 4u},
            "u16 or u32 per non-zero: global pixel k"},
           {"counts", t_.nnz(), "u8 per non-zero: count c, value c / s^2"},
           {"projection", p_.size() * std::uint64_t{4}, "f32 order^2 x M: P = pinv(B)"}}};
}

double ShProbeTransfer::flops_per_relight() const {
  return 2.0 * static_cast<double>(t_.nnz()) +
         2.0 * static_cast<double>(t_.rows()) * sh_count(order_);
}

LightCoeffs ShProbeTransfer::project_light(const Cubemap& radiance) const {
  if (radiance.layout.pixel_count() != static_cast<int>(t_.cols()))
    throw ParameterError(fmt::format("{}: the light has N = {}, the transfer N = {}", kName,
                                     radiance.layout.pixel_count(), t_.cols()));
  return {"pixel", radiance.light_vector()};
}

void ShProbeTransfer::relight(const LightCoeffs& light, LocalRadiance& out) const {
  check_pixel_light(light, t_.cols(), kName);
  const LocalRadiance pixel = relight_exact(t_, light.values);
  const int m = t_.local_count(), n = sh_count(order_);
  out = LocalRadiance(RadianceBasis::kSphericalHarmonics, n, t_.vertex_count());
  for (std::size_t v = 0; v < t_.vertex_count(); ++v)
    for (int i = 0; i < n; ++i) {
      Rgb acc(0.f);
      for (int j = 0; j < m; ++j)
        acc += p_[static_cast<std::size_t>(i) * m + j] * pixel.values[v * m + j];
      out.values[v * n + i] = acc;
    }
}

ModelRadiance ShProbeTransfer::model_radiance(const Cubemap& radiance) const {
  const LightCoeffs light = project_light(radiance);
  std::vector<Rgb> absolute(light.values.size());
  for (std::size_t k = 0; k < absolute.size(); ++k) absolute[k] = glm::abs(light.values[k]);
  const std::vector<Vec3d> tl = relight_exact_double(t_, light.values),
                           tl_abs = relight_exact_double(t_, absolute);
  const int m = t_.local_count(), n = sh_count(order_);
  const std::vector<double> b = sh_cell_integrals(HemisphereGrid(grid_side(m)), order_);
  ModelRadiance out;
  out.values.assign(t_.rows(), Vec3d(0.0));
  out.magnitude.assign(t_.rows(), Vec3d(0.0));
  std::vector<Vec3d> c(static_cast<std::size_t>(n)), ca(c.size());
  for (std::size_t v = 0; v < t_.vertex_count(); ++v) {
    for (int i = 0; i < n; ++i) {
      c[i] = ca[i] = Vec3d(0.0);
      for (int j = 0; j < m; ++j) {
        const double pij = p_[static_cast<std::size_t>(i) * m + j];
        c[i] += pij * tl[v * m + j];
        ca[i] += std::abs(pij) * tl_abs[v * m + j];
      }
    }
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < n; ++i) {
        const double bji = b[static_cast<std::size_t>(j) * n + i];
        out.values[v * m + j] += bji * c[i];
        out.magnitude[v * m + j] += std::abs(bji) * ca[i];
      }
  }
  return out;
}

std::unique_ptr<DeviceRelighter> ShProbeTransfer::upload(ClContext& context,
                                                         const ParamSet&) const {
  return upload_probe(context, *this);
}

void ShProbeTransfer::save(ArchiveWriter& w) const {
  w.add_meta("sh_probe_version", kStateVersion);
  w.add_meta("order", order_);
  w.add_meta("vertices", t_.vertex_count());
  w.add_meta("local_count", t_.local_count());
  w.add_meta("pixel_count", t_.cols());
  w.add_meta("supersampling", t_.supersampling());
  w.add_section("row_offsets", t_.row_offsets());
  std::vector<std::uint32_t> columns(t_.nnz());
  for (std::size_t i = 0; i < t_.nnz(); ++i) columns[i] = t_.column(i);
  w.add_indices("columns", columns, t_.narrow_columns());
  w.add_section("counts", t_.counts());
  w.add_section("projection", p_);
}

std::unique_ptr<CompressedTransfer> ShProbeTransfer::load(const ArchiveReader& r) {
  if (const int v = r.meta_value<int>("sh_probe_version"); v != kStateVersion)
    throw InputError(r.path(),
                     fmt::format("{} state version {} is not {}", kName, v, kStateVersion));
  const int order = r.meta_value<int>("order");
  if (order < 1 || order > 5) throw InputError(r.path(), "sh_probe: order out of 1..5");
  try {
    TransferMatrix t = TransferMatrix::from_csr(
        r.meta_value<std::size_t>("vertices"), r.meta_value<int>("local_count"),
        r.meta_value<int>("pixel_count"), r.meta_value<int>("supersampling"),
        r.section<std::uint32_t>("row_offsets"), r.indices("columns"),
        r.section<std::uint8_t>("counts"));
    auto out = std::make_unique<ShProbeTransfer>(std::move(t), order);
    if (r.section<float>("projection", out->p_.size()) != out->p_)
      throw InputError(r.path(), "sh_probe: the stored projection differs from pinv(B)");
    return out;
  } catch (const ParameterError& e) {
    throw InputError(r.path(), e.what());
  }
}

namespace {
CompressorEntry registry_entry() {
  CompressorEntry e;
  e.name = std::string(kName);
  e.description =
      "test-only: exact L* projected onto SH per vertex (least squares over the cell "
      "integrals), proving a non-pixel output basis is accepted everywhere";
  e.params = {{"order", ParamType::kInt, "3", 1.0, 5.0, {}, "SH order n (n^2 coefficients)"}};
  e.output_basis = RadianceBasis::kSphericalHarmonics;
  e.size_knob = SizeKnob{.key = "order", .direction = SizeKnob::Direction::kLargerIsMoreStorage};
  e.lossless = false;
  e.create = [](const ParamSet& p) -> std::unique_ptr<Compressor> {
    return std::make_unique<ShProbeCompressor>(static_cast<int>(p.get_int("order")));
  };
  e.load = &ShProbeTransfer::load;
  return e;
}
}  // namespace

PRT_REGISTER_COMPRESSOR(registry_entry);

}  // namespace prt::sh_probe
