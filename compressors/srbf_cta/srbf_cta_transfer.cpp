// The compressed srbf_cta transfer: storage and FLOP accounting, the light step, relight, and the
// archive format.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "prtlab/base/error.h"
#include "prtlab/lighting/srbf_light.h"
#include "prtlab/numeric/float16.h"
#include "prtlab/storage/archive.h"
#include "prtlab/storage/index_section.h"
#include "srbf_cta/srbf_cta.h"

namespace prt::srbf_cta {
namespace {

int cubemap_resolution(int pixels) {
  const int r = static_cast<int>(std::lround(std::sqrt(pixels / 6.0)));
  return r;
}

Precision precision_from(std::string_view s) {
  for (Precision p : {Precision::kFloat16, Precision::kFloat32})
    if (to_string(p) == s) return p;
  throw ParameterError(fmt::format("precision '{}' is none of float16, float32", s));
}

LightMode light_from(std::string_view s) {
  for (LightMode m : {LightMode::kUniform, LightMode::kScattered, LightMode::kPixel})
    if (to_string(m) == s) return m;
  throw ParameterError(fmt::format("light '{}' is none of uniform, scattered, pixel", s));
}

Signal signal_from(std::string_view s) {
  for (Signal v : {Signal::kCells, Signal::kBrdf})
    if (to_string(v) == s) return v;
  throw ParameterError(fmt::format("signal '{}' is none of cells, brdf", s));
}

/// n_l of the uniform light basis.
int uniform_light_count(const SrbfCtaArrays& a) {
  return a.light_srbfs == 0 ? a.srbf_count : a.light_srbfs;
}

std::vector<Rgb> to_rgb(const Eigen::MatrixXd& m) {  // n x 3
  std::vector<Rgb> out(static_cast<std::size_t>(m.rows()));
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    out[static_cast<std::size_t>(i)] =
        Rgb(static_cast<float>(m(i, 0)), static_cast<float>(m(i, 1)), static_cast<float>(m(i, 2)));
  return out;
}

}  // namespace

std::string_view to_string(Precision p) {
  return p == Precision::kFloat16 ? "float16" : "float32";
}

std::string_view to_string(LightMode m) {
  switch (m) {
    case LightMode::kUniform:
      return "uniform";
    case LightMode::kScattered:
      return "scattered";
    case LightMode::kPixel:
      return "pixel";
  }
  return "?";
}

std::string_view to_string(Signal s) {
  return s == Signal::kCells ? "cells" : "brdf";
}

std::size_t SrbfCtaArrays::id_bytes() const {
  return index_bytes(clusters());
}

SrbfCtaTransfer::SrbfCtaTransfer(SrbfCtaArrays arrays,
                                 std::shared_ptr<const SrbfProjector> projector)
    : a_(std::move(arrays)),
      basis_(transfer_basis(a_.srbf_count, a_.bandwidth)),
      transfer_projector_(std::move(projector)) {
  const CubemapLayout layout(cubemap_resolution(a_.pixel_count));
  if (!transfer_projector_)
    transfer_projector_ = std::make_shared<const SrbfProjector>(basis_, layout, a_.ridge);
  if (a_.light == LightMode::kUniform) {
    const int nl = uniform_light_count(a_);
    if (nl == a_.srbf_count) {
      light_projector_ = transfer_projector_;
    } else {
      SrbfBasis lb;
      lb.centres = uniform_sphere_points(nl);
      lb.bandwidths.assign(lb.centres.size(), uniform_gaussian_bandwidth(lb.centres));
      light_projector_ = std::make_shared<const SrbfProjector>(std::move(lb), layout, a_.ridge);
    }
    interpolation_ = srbf_inner_products(basis_, light_projector_->basis());
  }
}

std::string SrbfCtaTransfer::light_basis() const {
  return fmt::format("srbf{}", a_.srbf_count);
}

StorageReport SrbfCtaTransfer::storage() const {
  StorageReport r;
  const std::uint64_t b = a_.precision == Precision::kFloat16 ? 2 : 4;
  const std::string t = a_.precision == Precision::kFloat16 ? "IEEE half" : "f32";
  r.components.push_back(
      {"view_basis", a_.view_basis.size() * b, fmt::format("{}: U_view, M x R_view", t)});
  r.components.push_back({"light_bases", a_.light_bases.size() * b,
                          fmt::format("{} per cluster: U_light,c, n_t x R_light", t)});
  r.components.push_back({"dual_bases", a_.duals.size() * b,
                          fmt::format("{} per cluster: V_vert,c, R_vert x R_view R_light", t)});
  r.components.push_back({"cluster_ids", a_.vertices * a_.id_bytes(),
                          fmt::format("u{} per vertex", 8 * a_.id_bytes())});
  r.components.push_back(
      {"weights", a_.weights.size() * b, fmt::format("{} per vertex: W_x, R_vert", t)});
  return r;
}

double SrbfCtaTransfer::flops_per_relight() const {
  const double nt = a_.srbf_count, r1 = a_.rank_view, r2 = a_.rank_light, r3 = a_.rank_vertex,
               m = a_.local_count, c = static_cast<double>(a_.clusters()),
               v = static_cast<double>(a_.vertices);
  double light = 0;
  switch (a_.light) {
    case LightMode::kUniform:
      light = 2.0 * nt * uniform_light_count(a_);
      break;
    case LightMode::kScattered:
      light = 2.0 * nt * (a_.light_srbfs == 0 ? 162 : a_.light_srbfs);
      break;
    case LightMode::kPixel:
      light = 2.0 * nt * a_.pixel_count;
      break;
  }
  return light + c * (2 * nt * r2 + 2 * r3 * r1 * r2 + 2 * m * r1 * r3) + v * 2 * m * r3;
}

Eigen::MatrixXd SrbfCtaTransfer::light_products(const Cubemap& radiance) const {
  if (radiance.layout.pixel_count() != a_.pixel_count)
    throw ParameterError(fmt::format("{}: a light of {} pixels for a transfer of {}", kName,
                                     radiance.layout.pixel_count(), a_.pixel_count));
  const auto n = static_cast<Eigen::Index>(a_.pixel_count);
  Eigen::MatrixXd rad(n, 3);
  for (Eigen::Index k = 0; k < n; ++k)
    for (int ch = 0; ch < 3; ++ch) rad(k, ch) = radiance.radiance[static_cast<std::size_t>(k)][ch];
  switch (a_.light) {
    case LightMode::kPixel:
      return transfer_projector_->pixel_weights().transpose() * rad;
    case LightMode::kUniform: {
      Eigen::MatrixXd coeffs(static_cast<Eigen::Index>(light_projector_->basis().size()), 3);
      for (int ch = 0; ch < 3; ++ch) {
        const Eigen::VectorXd f = rad.col(ch);
        coeffs.col(ch) = light_projector_->project(std::span<const double>(f.data(), f.size()));
      }
      return interpolation_ * coeffs;
    }
    case LightMode::kScattered: {
      ScatteredFitOptions o;
      o.count = a_.light_srbfs == 0 ? 162 : a_.light_srbfs;
      o.rounds = a_.light_rounds;
      const SrbfLight fit = fit_scattered_srbf(radiance, o);
      SrbfBasis lb;
      lb.centres = fit.centres;
      lb.bandwidths = fit.bandwidths;
      Eigen::MatrixXd coeffs(static_cast<Eigen::Index>(fit.count()), 3);
      for (std::size_t j = 0; j < fit.count(); ++j)
        for (int ch = 0; ch < 3; ++ch)
          coeffs(static_cast<Eigen::Index>(j), ch) = fit.coefficients[j][ch];
      return srbf_inner_products(basis_, lb) * coeffs;
    }
  }
  return Eigen::MatrixXd::Zero(a_.srbf_count, 3);
}

LightCoeffs SrbfCtaTransfer::project_light(const Cubemap& radiance) const {
  return LightCoeffs{light_basis(), to_rgb(light_products(radiance))};
}

Eigen::MatrixXd SrbfCtaTransfer::light_operator() const {
  const CubemapLayout layout(cubemap_resolution(a_.pixel_count));
  Eigen::MatrixXd g;
  if (a_.light == LightMode::kUniform) {
    // L' = E (A_l + alpha I)^-1 W_l^T f for the radiance f = L / Omega, so G = diag(1 / Omega)
    // W_l S with S = (A_l + alpha I)^-1 E^T: n_t right-hand sides, not N.
    g = light_projector_->pixel_weights() * light_projector_->solve(interpolation_.transpose());
  } else {
    g = transfer_projector_->pixel_weights();
  }
  for (Eigen::Index k = 0; k < g.rows(); ++k) g.row(k) /= layout.solid_angle(static_cast<int>(k));
  return g;
}

void SrbfCtaTransfer::check_light(const LightCoeffs& light) const {
  if (light.basis != light_basis() ||
      light.values.size() != static_cast<std::size_t>(a_.srbf_count))
    throw ParameterError(fmt::format(
        "{}: the light is in basis '{}' with {} values, the transfer needs '{}' with {}", kName,
        light.basis, light.values.size(), light_basis(), a_.srbf_count));
}

void SrbfCtaTransfer::relight(const LightCoeffs& light, LocalRadiance& out) const {
  check_light(light);
  out.ensure_shape(RadianceBasis::kPixel, a_.local_count, a_.vertices);
  const std::vector<Rgb> q = cluster_matrices(a_, light.values);
  blend_vertices(a_, q, {}, true, out.values);
}

void SrbfCtaTransfer::relight_vertices(const LightCoeffs& light,
                                       std::span<const std::uint32_t> vertices,
                                       LocalRadiance& out) const {
  check_light(light);
  check_vertex_subset(vertices, a_.vertices, kName);
  out.ensure_shape(RadianceBasis::kPixel, a_.local_count, a_.vertices);
  const std::vector<Rgb> q = cluster_matrices(a_, light.values);
  blend_vertices(a_, q, vertices, false, out.values);
}

std::unique_ptr<DeviceRelighter> SrbfCtaTransfer::upload(ClContext& context,
                                                         const ParamSet&) const {
  return upload_srbf_cta(context, a_, light_basis());
}

namespace {

void add_values(ArchiveWriter& w, const std::string& name, const std::vector<float>& v,
                Precision p) {
  if (p == Precision::kFloat32) {
    w.add_section(name, v);
    return;
  }
  std::vector<std::uint16_t> h(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) h[i] = float_to_half(v[i]);
  w.add_section(name, std::move(h));
}

std::vector<float> read_values(const ArchiveReader& r, const std::string& name, std::uint64_t n,
                               Precision p) {
  if (p == Precision::kFloat32) return r.section<float>(name, n);
  const auto h = r.view<std::uint16_t>(name, n);
  std::vector<float> v(h.size());
  for (std::size_t i = 0; i < h.size(); ++i) v[i] = half_to_float(h[i]);
  return v;
}

}  // namespace

void SrbfCtaTransfer::save(ArchiveWriter& w) const {
  w.add_meta("srbf_cta_version", kStateVersion);
  w.add_meta("vertices", a_.vertices);
  w.add_meta("local_count", a_.local_count);
  w.add_meta("pixel_count", a_.pixel_count);
  w.add_meta("srbf_count", a_.srbf_count);
  w.add_meta("bandwidth", a_.bandwidth);
  w.add_meta("ridge", a_.ridge);
  w.add_meta("rank_view", a_.rank_view);
  w.add_meta("rank_light", a_.rank_light);
  w.add_meta("rank_vertex", a_.rank_vertex);
  w.add_meta("clusters", a_.clusters());
  w.add_meta("precision", std::string(to_string(a_.precision)));
  w.add_meta("light", std::string(to_string(a_.light)));
  w.add_meta("light_srbfs", a_.light_srbfs);
  w.add_meta("light_rounds", a_.light_rounds);
  w.add_meta("signal", std::string(to_string(a_.signal)));
  w.add_meta("brdf_terms", a_.brdf_terms);
  w.add_meta("frobenius_error", a_.frobenius_error);
  w.add_meta("srbf_frobenius_error", a_.srbf_frobenius_error);
  add_values(w, "view_basis", a_.view_basis, a_.precision);
  add_values(w, "light_bases", a_.light_bases, a_.precision);
  add_values(w, "dual_bases", a_.duals, a_.precision);
  add_values(w, "weights", a_.weights, a_.precision);
  add_index_section(w, "cluster_ids", a_.ids, a_.clusters());
}

std::unique_ptr<CompressedTransfer> SrbfCtaTransfer::load(const ArchiveReader& r) {
  const auto fail = [&](const std::string& problem) {
    return InputError(r.path(), fmt::format("{}: {}", kName, problem));
  };
  const int version = r.meta_value<int>("srbf_cta_version");
  if (version != kStateVersion)
    throw fail(fmt::format(
        "state version {} is not the version {} this build reads{}", version, kStateVersion,
        version < kStateVersion ? " (older versions declare the error of the pixel-quadrature "
                                  "light step whatever the light mode, or lack the signal; "
                                  "compress the transfer again)"
                                : ""));
  SrbfCtaArrays a;
  a.vertices = r.meta_value<std::size_t>("vertices");
  a.local_count = r.meta_value<int>("local_count");
  a.pixel_count = r.meta_value<int>("pixel_count");
  a.srbf_count = r.meta_value<int>("srbf_count");
  a.bandwidth = r.meta_value<double>("bandwidth");
  a.ridge = r.meta_value<double>("ridge");
  a.rank_view = r.meta_value<int>("rank_view");
  a.rank_light = r.meta_value<int>("rank_light");
  a.rank_vertex = r.meta_value<int>("rank_vertex");
  const auto clusters = r.meta_value<std::size_t>("clusters");
  a.light_srbfs = r.meta_value<int>("light_srbfs");
  a.light_rounds = r.meta_value<int>("light_rounds");
  a.brdf_terms = r.meta_value<int>("brdf_terms");
  a.frobenius_error = r.meta_value<double>("frobenius_error");
  a.srbf_frobenius_error = r.meta_value<double>("srbf_frobenius_error");
  try {
    a.precision = precision_from(r.meta_value<std::string>("precision"));
    a.light = light_from(r.meta_value<std::string>("light"));
    a.signal = signal_from(r.meta_value<std::string>("signal"));
    transfer_basis(a.srbf_count, 1.0);
  } catch (const ParameterError& e) {
    throw fail(e.what());
  }
  const int res = cubemap_resolution(a.pixel_count);
  if (a.local_count <= 0 || a.pixel_count <= 0 || 6 * res * res != a.pixel_count)
    throw fail(
        fmt::format("bad shape: M = {}, N = {} (N must be 6 R^2)", a.local_count, a.pixel_count));
  if ((a.signal == Signal::kBrdf) != (a.brdf_terms > 0) || a.brdf_terms > a.local_count)
    throw fail(fmt::format("{} BRDF terms for the {} signal of M = {} cells", a.brdf_terms,
                           to_string(a.signal), a.local_count));
  if (a.rank_view < 1 || a.rank_view > a.local_count || a.rank_light < 1 ||
      a.rank_light > a.srbf_count || a.rank_vertex < 1 ||
      a.rank_vertex > a.rank_view * a.rank_light)
    throw fail(fmt::format("ranks ({}, {}, {}) do not fit M = {}, n_t = {}", a.rank_view,
                           a.rank_light, a.rank_vertex, a.local_count, a.srbf_count));
  if (!(a.bandwidth > 0) || !std::isfinite(a.bandwidth) || !(a.ridge >= 0) ||
      !std::isfinite(a.ridge) || a.light_srbfs < 0 || a.light_rounds < 1)
    throw fail("the bandwidth, ridge or light settings are out of range");
  if (!(std::isfinite(a.frobenius_error) && a.frobenius_error >= 0 &&
        std::isfinite(a.srbf_frobenius_error) && a.srbf_frobenius_error >= 0))
    throw fail("an error is not a finite non-negative number");
  constexpr std::uint64_t kU32 = std::numeric_limits<std::uint32_t>::max();
  if (a.vertices == 0 || clusters == 0 || clusters > a.vertices ||
      a.vertices > kU32 / static_cast<std::uint64_t>(a.local_count))
    throw fail(fmt::format("{} vertices and {} clusters do not fit the relight's u32 indices",
                           a.vertices, clusters));
  const std::uint64_t r1 = static_cast<std::uint64_t>(a.rank_view), r2 = a.rank_light,
                      r3 = a.rank_vertex, nt = a.srbf_count;
  if (clusters * nt * r2 > kU32 || clusters * r3 * r1 * r2 > kU32 ||
      clusters * static_cast<std::uint64_t>(a.local_count) * r3 > kU32)
    throw fail("the cluster bases exceed the relight's u32 indices");
  a.view_basis = read_values(r, "view_basis", a.local_count * r1, a.precision);
  a.light_bases = read_values(r, "light_bases", clusters * nt * r2, a.precision);
  a.duals = read_values(r, "dual_bases", clusters * r3 * r1 * r2, a.precision);
  a.weights = read_values(r, "weights", a.vertices * r3, a.precision);
  a.ids = read_index_section(r, "cluster_ids", a.vertices, clusters);
  const auto finite = [](float v) { return std::isfinite(v); };
  for (const auto* v : {&a.view_basis, &a.light_bases, &a.duals, &a.weights})
    if (!std::all_of(v->begin(), v->end(), finite)) throw fail("a stored value is not finite");
  try {
    return std::make_unique<SrbfCtaTransfer>(std::move(a));
  } catch (const ParameterError& e) {
    throw fail(e.what());
  }
}

}  // namespace prt::srbf_cta
