#include "cpca_sh/cpca_sh.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/numeric/float16.h"
#include "prtlab/sphere/hemisphere_projection.h"
#include "prtlab/sphere/spherical_harmonics.h"
#include "prtlab/storage/archive.h"
#include "prtlab/storage/index_section.h"
#include "prtlab/transfer/sh_transfer.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt::cpca_sh {
namespace {

void to_hemisphere_metric(std::vector<double>& x, const CpcaShArrays& shape);

struct CpcaShParams {
  ClusteredPcaOptions options;
  WeightFormat format = WeightFormat::kFloat32;
  Projection projection = Projection::kLeastSquares;
  Metric metric = Metric::kHemisphere;
  Signal signal = Signal::kMatrix;
  int order = kInputOrder;
  int output_order = kInputOrder;
};

class CpcaShCompressor final : public Compressor {
 public:
  explicit CpcaShCompressor(CpcaShParams p) : p_(std::move(p)) {}

  std::unique_ptr<CompressedTransfer> compress(const TransferInput& input,
                                               Progress& progress) const override {
    check_transfer_shape(input, kName);
    const TransferMatrix& t = input.transfer;
    if (input.sh == nullptr)
      throw ParameterError(
          fmt::format("{}: the input holds no SH transfer (the entry asks for "
                      "order {})",
                      kName, kInputOrder));
    const ShTransfer& sh = *input.sh;
    if (sh.order() < p_.order)
      throw ParameterError(
          fmt::format("{}: order = {} needs an SH transfer of order {} or more, "
                      "the input has order {}",
                      kName, p_.order, p_.order, sh.order()));
    if (sh.vertex_count() != t.vertex_count())
      throw ParameterError(fmt::format("{}: the SH transfer has {} vertices, T {}", kName,
                                       sh.vertex_count(), t.vertex_count()));
    if (t.vertex_count() == 0)
      throw ParameterError(fmt::format("{}: the transfer has no vertices", kName));
    const bool diffuse = p_.signal == Signal::kDiffuse;
    if (diffuse && sh.order() < 2)
      throw ParameterError(fmt::format(
          "{}: signal = diffuse needs the cosine row of an SH transfer of order 2 or more, the "
          "input has order {}",
          kName, sh.order()));

    CpcaShArrays shape;
    shape.vertices = t.vertex_count();
    shape.order = p_.order;
    // The diffuse signal is a vector over the whole sphere of light directions: one output row,
    // the zero-hemisphere M_p it is exact for, and the Euclidean (the paper's) norm.
    shape.output_order = diffuse ? 1 : p_.output_order;
    shape.projection = diffuse ? Projection::kZero : p_.projection;
    shape.metric = diffuse ? Metric::kSphere : p_.metric;
    shape.method = p_.options.method;
    shape.format = p_.format;
    shape.signal = p_.signal;
    const std::size_t dim = shape.signal_dim();
    std::vector<double> x = diffuse
                                ? diffuse_transfer_signals(sh, p_.order)
                                : transfer_signals(sh, p_.order, p_.output_order, p_.projection);
    if (shape.metric == Metric::kHemisphere) to_hemisphere_metric(x, shape);
    const RowSet signals = RowSet::dense(std::span<const double>(x), shape.vertices, dim);

    ClusteredPcaOptions o = p_.options;
    // A small transfer gets what it can hold: one vertex per cluster at most, and no more
    // vectors than the signal has dimensions (README, "Parameters").
    o.clusters = static_cast<int>(std::min<std::size_t>(o.clusters, shape.vertices));
    o.components = static_cast<int>(std::min<std::size_t>(o.components, dim));
    const std::int64_t planned =
        2 + (o.method == CpcaMethod::kStatic
                 ? 0
                 : std::int64_t{o.components} * o.iterations_per_component +
                       (o.method == CpcaMethod::kAdaptive ? o.adaptive_iterations : 0));
    std::int64_t passes = 0;
    const auto rows_total = static_cast<std::int64_t>(t.rows());
    o.on_pass = [&](const CpcaPass& pass) {
      log_debug("{}: {} pass {} ({} vectors): squared error {:.6g}, {} vertices moved", kName,
                pass.stage, pass.iteration, pass.components, pass.squared_error, pass.reassigned);
      const std::int64_t before = rows_total * passes / planned;
      passes = std::min(planned, passes + 1);
      progress.advance(rows_total * passes / planned - before);
    };
    const ClusteredPca model = clustered_pca(signals, o);
    CpcaShArrays stored = encode(model, signals, std::move(shape));
    declare_model_error(stored, input);
    auto out = std::make_unique<CpcaShTransfer>(std::move(stored));
    log_debug("{}: {} clusters, {} weights, signal error {:.4g}", kName, model.clusters.size(),
              model.weight_count(), out->arrays().signal_error);
    progress.finish();
    return out;
  }

 private:
  CpcaShParams p_;
};

// X_p -> A^(1/2) X_p for every vertex, in place: Euclidean distances of the results are the
// squared errors over the hemisphere.
void to_hemisphere_metric(std::vector<double>& x, const CpcaShArrays& shape) {
  const Eigen::MatrixXd root = hemisphere_gram_root(shape.output_order, false);
  const Eigen::Index rows = shape.rows(), n = shape.n();
  using Block = Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;
  tbb::parallel_for(std::size_t{0}, shape.vertices, [&](std::size_t v) {
    Block m(x.data() + v * shape.signal_dim(), rows, n);
    m = (root * m).eval();
  });
}

Metric metric_from(std::string_view name) {
  for (Metric m : {Metric::kSphere, Metric::kHemisphere})
    if (to_string(m) == name) return m;
  throw ParameterError(fmt::format("{}: metric '{}' is none of sphere, hemisphere", kName, name));
}

Signal signal_from(std::string_view name) {
  for (Signal s : {Signal::kMatrix, Signal::kDiffuse})
    if (to_string(s) == name) return s;
  throw ParameterError(fmt::format("{}: signal '{}' is none of matrix, diffuse", kName, name));
}

CpcaMethod method_from(std::string_view name) {
  for (CpcaMethod m : {CpcaMethod::kStatic, CpcaMethod::kIterative, CpcaMethod::kAdaptive})
    if (to_string(m) == name) return m;
  throw ParameterError(
      fmt::format("{}: method '{}' is none of static, iterative, adaptive", kName, name));
}

WeightFormat weight_format_from(std::string_view name) {
  for (WeightFormat f : {WeightFormat::kFloat32, WeightFormat::kFloat16, WeightFormat::kS8})
    if (to_string(f) == name) return f;
  throw ParameterError(
      fmt::format("{}: weight format '{}' is none of float32, float16, s8", kName, name));
}

Projection projection_from(std::string_view name) {
  for (Projection p : {Projection::kZero, Projection::kLeastSquares})
    if (to_string(p) == name) return p;
  throw ParameterError(
      fmt::format("{}: projection '{}' is none of zero, least_squares", kName, name));
}

}  // namespace

std::string_view to_string(Signal s) {
  return s == Signal::kDiffuse ? "diffuse" : "matrix";
}

std::string_view to_string(WeightFormat f) {
  switch (f) {
    case WeightFormat::kFloat32:
      return "float32";
    case WeightFormat::kFloat16:
      return "float16";
    case WeightFormat::kS8:
      return "s8";
  }
  return "?";
}

std::string_view to_string(Projection p) {
  return p == Projection::kZero ? "zero" : "least_squares";
}

std::string_view to_string(Metric m) {
  return m == Metric::kSphere ? "sphere" : "hemisphere";
}

Eigen::MatrixXd hemisphere_gram_root(int order, bool inverse) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(hemisphere_gram(order));
  const Eigen::VectorXd s = inverse ? eig.eigenvalues().cwiseSqrt().cwiseInverse().eval()
                                    : eig.eigenvalues().cwiseSqrt().eval();
  return eig.eigenvectors() * s.asDiagonal() * eig.eigenvectors().transpose();
}

std::string_view to_string(CpcaMethod m) {
  switch (m) {
    case CpcaMethod::kStatic:
      return "static";
    case CpcaMethod::kIterative:
      return "iterative";
    case CpcaMethod::kAdaptive:
      return "adaptive";
  }
  return "?";
}

std::size_t CpcaShArrays::id_bytes() const {
  return index_bytes(clusters());
}

int CpcaShArrays::uniform_vectors() const {
  if (clusters() == 0) return -1;
  const int k = vectors_of(0);
  for (std::size_t c = 1; c < clusters(); ++c)
    if (vectors_of(c) != k) return -1;
  return k;
}

std::vector<double> transfer_signals(const ShTransfer& sh, int order, int output_order,
                                     Projection projection) {
  PRT_CHECK(order >= 1 && order <= sh.order() && output_order >= 1 && output_order <= order,
            "transfer_signals: order {} and output order {} for an SH transfer of order {}", order,
            output_order, sh.order());
  const int n = order * order, rows = output_order * output_order, full = sh.dim();
  const std::size_t dim = static_cast<std::size_t>(rows) * n;
  std::vector<double> x(sh.vertex_count() * dim);
  // The least-squares coefficients of order output_order need only the zero-hemisphere ones of
  // that order, b_i for i < rows: the leading rows of M_p.
  const std::optional<HemisphereProjector> projector =
      projection == Projection::kLeastSquares
          ? std::optional<HemisphereProjector>(HemisphereProjector(output_order))
          : std::nullopt;
  tbb::parallel_for(std::size_t{0}, sh.vertex_count(), [&](std::size_t v) {
    const std::span<const double> m = sh.matrix(v);
    double* out = x.data() + v * dim;
    if (!projector) {
      for (int i = 0; i < rows; ++i)
        for (int k = 0; k < n; ++k)
          out[static_cast<std::size_t>(i) * n + k] = m[static_cast<std::size_t>(i) * full + k];
      return;
    }
    Eigen::VectorXd b(rows);
    for (int k = 0; k < n; ++k) {
      for (int i = 0; i < rows; ++i) b[i] = m[static_cast<std::size_t>(i) * full + k];
      const Eigen::VectorXd c = projector->solve(b);
      for (int i = 0; i < rows; ++i) out[static_cast<std::size_t>(i) * n + k] = c[i];
    }
  });
  return x;
}

std::vector<double> diffuse_transfer_signals(const ShTransfer& sh, int order) {
  PRT_CHECK(order >= 1 && order <= sh.order() && sh.order() >= 2,
            "diffuse_transfer_signals: order {} for an SH transfer of order {}", order, sh.order());
  const int n = order * order, full = sh.dim();
  // Row sh_index(1, 0) = 2 of M_p: y_{1,0}(F^T d) = sqrt(3 / (4 pi)) (d . n).
  const std::size_t row = 2;
  const double scale = std::sqrt(4.0 * std::numbers::pi / 3.0);
  std::vector<double> x(sh.vertex_count() * static_cast<std::size_t>(n));
  tbb::parallel_for(std::size_t{0}, sh.vertex_count(), [&](std::size_t v) {
    const std::span<const double> m = sh.matrix(v);
    for (int k = 0; k < n; ++k)
      x[v * static_cast<std::size_t>(n) + k] = scale * m[row * static_cast<std::size_t>(full) + k];
  });
  return x;
}

void derive_vertex_layout(CpcaShArrays& a) {
  const std::size_t vertices = a.ids.size();
  a.weight_offsets.assign(vertices + 1, 0);
  std::uint64_t total = 0;
  for (std::size_t p = 0; p < vertices; ++p) {
    total += static_cast<std::uint64_t>(a.vectors_of(a.ids[p]));
    if (total > std::numeric_limits<std::uint32_t>::max()) {
      throw ParameterError(
          fmt::format("{}: {} weights exceed the u32 offsets of the relight", kName, total));
    }
    a.weight_offsets[p + 1] = static_cast<std::uint32_t>(total);
  }
  a.weight_values.resize(total);
  for (std::size_t i = 0; i < total; ++i) {
    switch (a.format) {
      case WeightFormat::kFloat32:
        a.weight_values[i] = a.weights32[i];
        break;
      case WeightFormat::kFloat16:
        a.weight_values[i] = half_to_float(a.weights16[i]);
        break;
      case WeightFormat::kS8:
        a.weight_values[i] = static_cast<float>(a.codes[i]);
        break;
    }
  }
}

CpcaShArrays encode(const ClusteredPca& model, const RowSet& points, CpcaShArrays a) {
  const std::size_t dim = a.signal_dim();
  PRT_CHECK(points.cols() == dim && points.rows() == a.vertices,
            "cpca_sh encode: {} x {} points for {} vertices of dimension {}", points.rows(),
            points.cols(), a.vertices, dim);
  const Eigen::Index rows = a.rows(), n = a.n();
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const bool hemisphere = a.metric == Metric::kHemisphere;
  const Eigen::MatrixXd root = hemisphere ? hemisphere_gram_root(a.output_order, false)
                                          : Eigen::MatrixXd::Identity(rows, rows);
  const Eigen::MatrixXd inverse_root = hemisphere ? hemisphere_gram_root(a.output_order, true)
                                                  : Eigen::MatrixXd::Identity(rows, rows);
  // A representative of the points (rows x n, row-major) as the matrix the relight multiplies.
  const auto store = [&](const Eigen::VectorXd& point, float* out) {
    const RowMajor x = inverse_root * Eigen::Map<const RowMajor>(point.data(), rows, n);
    for (std::size_t j = 0; j < dim; ++j) out[j] = static_cast<float>(x.data()[j]);
  };
  a.first.assign(model.clusters.size() + 1, 0);
  for (std::size_t c = 0; c < model.clusters.size(); ++c)
    a.first[c + 1] = a.first[c] + 1 + static_cast<std::uint32_t>(model.clusters[c].k());
  a.reps.resize(static_cast<std::size_t>(a.first.back()) * dim);
  for (std::size_t c = 0; c < model.clusters.size(); ++c) {
    const CpcaCluster& cl = model.clusters[c];
    float* rep = a.reps.data() + static_cast<std::size_t>(a.first[c]) * dim;
    store(cl.mean, rep);
    for (int i = 0; i < cl.k(); ++i)
      store(cl.components.col(i), rep + static_cast<std::size_t>(i + 1) * dim);
  }
  a.ids = model.assignments;
  const std::size_t total = model.weights.size();
  a.weights32.clear();
  a.weights16.clear();
  a.codes.clear();
  a.vertex_scales.clear();
  switch (a.format) {
    case WeightFormat::kFloat32:
      a.weights32.resize(total);
      for (std::size_t i = 0; i < total; ++i) a.weights32[i] = static_cast<float>(model.weights[i]);
      break;
    case WeightFormat::kFloat16:
      a.weights16.resize(total);
      for (std::size_t i = 0; i < total; ++i) {
        if (!(std::abs(model.weights[i]) <= 65504.0))
          throw ParameterError(fmt::format(
              "{}: weight {} does not fit an IEEE half (|w| <= 65504); use weights=float32 or s8",
              kName, model.weights[i]));
        a.weights16[i] = float_to_half(static_cast<float>(model.weights[i]));
      }
      break;
    case WeightFormat::kS8: {
      a.codes.resize(total);
      a.vertex_scales.resize(a.vertices);
      for (std::size_t p = 0; p < a.vertices; ++p) {
        const std::uint64_t b = model.weight_offsets[p], e = model.weight_offsets[p + 1];
        double top = 0.0;
        for (std::uint64_t i = b; i < e; ++i) top = std::max(top, std::abs(model.weights[i]));
        float scale = static_cast<float>(top / 127.0);
        // A weight range below float's smallest normal (or zero) keeps scale 1: all codes 0.
        if (!(scale >= std::numeric_limits<float>::min()) || !std::isfinite(scale)) scale = 1.0f;
        a.vertex_scales[p] = scale;
        for (std::uint64_t i = b; i < e; ++i) {
          const double q = std::nearbyint(model.weights[i] / static_cast<double>(scale));
          a.codes[i] = static_cast<std::int8_t>(std::clamp(q, -127.0, 127.0));
        }
      }
      break;
    }
  }
  derive_vertex_layout(a);
  // The error of the model as stored: f32 representatives, the weights as the relight reads
  // them (s8 codes times the vertex's scale).
  RowMajorMatrixXd reps(static_cast<Eigen::Index>(a.first.back()), static_cast<Eigen::Index>(dim));
  for (Eigen::Index r = 0; r < reps.rows(); ++r) {
    RowMajor x(rows, n);
    for (std::size_t j = 0; j < dim; ++j)
      x.data()[j] = a.reps[static_cast<std::size_t>(r) * dim + j];
    const RowMajor y = root * x;
    for (std::size_t j = 0; j < dim; ++j) reps(r, static_cast<Eigen::Index>(j)) = y.data()[j];
  }
  std::vector<double> w(a.weight_values.size());
  for (std::size_t p = 0; p < a.vertices; ++p) {
    const double scale = a.format == WeightFormat::kS8 ? a.vertex_scales[p] : 1.0;
    for (std::uint32_t i = a.weight_offsets[p]; i < a.weight_offsets[p + 1]; ++i)
      w[i] = static_cast<double>(a.weight_values[i]) * scale;
  }
  const std::vector<std::uint64_t> offsets(a.weight_offsets.begin(), a.weight_offsets.end());
  const double se = affine_codebook_squared_error(points, a.ids, reps, a.first, w, offsets);
  a.signal_error = model.total_squared_norm > 0 ? std::sqrt(se / model.total_squared_norm) : 0.0;
  a.signal_squared_error = se;
  a.signal_squared_norm = model.total_squared_norm;
  return a;
}

std::string CpcaShTransfer::light_basis() const {
  return fmt::format("sh{}", a_.order);
}

StorageReport CpcaShTransfer::storage() const {
  StorageReport r;
  const std::uint64_t vertices = a_.vertices;
  r.components.push_back({"cluster_ids", vertices * a_.id_bytes(),
                          fmt::format("u{} per vertex: its cluster", 8 * a_.id_bytes())});
  const std::uint64_t w = a_.weight_values.size();
  switch (a_.format) {
    case WeightFormat::kFloat32:
      r.components.push_back({"weights", w * 4, "f32 per vertex and vector of its cluster: w_i"});
      break;
    case WeightFormat::kFloat16:
      r.components.push_back(
          {"weights", w * 2, "IEEE half per vertex and vector of its cluster: w_i, nearest even"});
      break;
    case WeightFormat::kS8:
      r.components.push_back(
          {"weights", w,
           "s8 code q per vertex and vector: w_i = q * the vertex's scale, |q| <= 127"});
      r.components.push_back(
          {"vertex_scales", vertices * 4, "f32 per vertex: max |w_i| / 127 (the value of q = 1)"});
      break;
  }
  r.components.push_back(
      {"representatives", a_.reps.size() * std::uint64_t{4},
       fmt::format("f32 {} x {} matrix (local SH i x light SH k, row-major) per cluster mean and "
                   "per cluster vector, cluster after cluster",
                   a_.rows(), a_.n())});
  if (a_.uniform_vectors() < 0) {
    r.components.push_back(
        {"vector_counts", a_.clusters() * std::uint64_t{2}, "u16 per cluster: its k_c (adaptive)"});
  }
  return r;
}

double CpcaShTransfer::flops_per_relight() const {
  const double rows = a_.rows();
  const double per_rep = 2.0 * rows * a_.n();
  const double blend =
      2.0 * rows * static_cast<double>(a_.weight_values.size()) +
      (a_.format == WeightFormat::kS8 ? rows * static_cast<double>(a_.vertices) : 0.0);
  return per_rep * static_cast<double>(a_.rep_count()) + blend;
}

LightCoeffs CpcaShTransfer::project_light(const Cubemap& radiance) const {
  const ShCoeffs sh = sh_project(radiance, a_.order);
  LightCoeffs out{light_basis(), std::vector<Rgb>(sh.coeffs.size())};
  for (std::size_t k = 0; k < sh.coeffs.size(); ++k) out.values[k] = Rgb(sh.coeffs[k]);
  return out;
}

void CpcaShTransfer::check_light(const LightCoeffs& light) const {
  if (light.basis != light_basis() || light.values.size() != static_cast<std::size_t>(a_.n())) {
    throw ParameterError(
        fmt::format("{}: the light is in basis '{}' with {} values, the transfer "
                    "needs '{}' with {}",
                    kName, light.basis, light.values.size(), light_basis(), a_.n()));
  }
}

void CpcaShTransfer::shape_output(LocalRadiance& out) const {
  if (out.basis != RadianceBasis::kSphericalHarmonics || out.dim != a_.rows() ||
      out.vertices != a_.vertices ||
      out.values.size() != a_.vertices * static_cast<std::size_t>(a_.rows())) {
    out = LocalRadiance(RadianceBasis::kSphericalHarmonics, a_.rows(), a_.vertices);
  }
}

std::vector<BackendMetric> CpcaShTransfer::backend_metrics() const {
  const std::string norm =
      a_.signal == Signal::kDiffuse
          ? "the diffuse transfer vectors t_p (Euclidean)"
          : fmt::format("the {} x {} transfer matrices X_p ({} norm)", a_.rows(), a_.n(),
                        a_.metric == Metric::kHemisphere ? "hemisphere" : "Euclidean");
  return {
      {"signal_squared_error", a_.signal_squared_error,
       fmt::format("sum over vertices of ||X~_p - X_p||^2 of {}, the model as stored", norm)},
      {"signal_squared_norm", a_.signal_squared_norm,
       fmt::format("sum over vertices of ||X_p||^2 of {}", norm)},
      {"signal_relative_error", a_.signal_error,
       "sqrt(signal_squared_error / signal_squared_norm)"},
      {"cost_model_floats", static_cast<double>(a_.weight_values.size() + a_.reps.size()),
       "the paper's storage cost (section 4.1): per-vertex weights plus representative values, "
       "m_p n' + m_c (n' + 1) n for uniform counts"},
  };
}

std::vector<Rgb> scaled_light(const CpcaShArrays& a, std::span<const Rgb> light) {
  std::vector<Rgb> l(light.begin(), light.end());
  const float s = a.light_scale();
  if (s != 1.0f)
    for (Rgb& v : l) v *= s;
  return l;
}

void CpcaShTransfer::relight(const LightCoeffs& light, LocalRadiance& out) const {
  check_light(light);
  shape_output(out);
  const std::vector<Rgb> q = representative_products(a_, scaled_light(a_, light.values));
  blend_vertices(a_, q, out.values);
}

void CpcaShTransfer::relight_vertices(const LightCoeffs& light,
                                      std::span<const std::uint32_t> vertices,
                                      LocalRadiance& out) const {
  check_light(light);
  check_vertex_subset(vertices, a_.vertices, kName);
  shape_output(out);
  const std::vector<Rgb> q = representative_products(a_, scaled_light(a_, light.values));
  blend_vertex_subset(a_, q, vertices, out.values);
}

std::unique_ptr<DeviceRelighter> CpcaShTransfer::upload(ClContext& context, const ParamSet&) const {
  return upload_cpca_sh(context, a_, light_basis());
}

void CpcaShTransfer::save(ArchiveWriter& archive) const {
  archive.add_meta("cpca_sh_version", kStateVersion);
  archive.add_meta("vertices", a_.vertices);
  archive.add_meta("order", a_.order);
  archive.add_meta("output_order", a_.output_order);
  archive.add_meta("projection", std::string(to_string(a_.projection)));
  archive.add_meta("metric", std::string(to_string(a_.metric)));
  archive.add_meta("clusters", a_.clusters());
  archive.add_meta("method", std::string(to_string(a_.method)));
  archive.add_meta("weights", std::string(to_string(a_.format)));
  archive.add_meta("signal_error", a_.signal_error);
  archive.add_meta("local_count", a_.local_count);
  archive.add_meta("frobenius_error", a_.frobenius_error);
  archive.add_meta("signal", std::string(to_string(a_.signal)));
  archive.add_meta("signal_squared_error", a_.signal_squared_error);
  archive.add_meta("signal_squared_norm", a_.signal_squared_norm);
  std::vector<std::uint16_t> counts(a_.clusters());
  for (std::size_t c = 0; c < a_.clusters(); ++c)
    counts[c] = static_cast<std::uint16_t>(a_.vectors_of(c));
  archive.add_section("vector_counts", std::move(counts));
  add_index_section(archive, "cluster_ids", a_.ids, a_.clusters());
  switch (a_.format) {
    case WeightFormat::kFloat32:
      archive.add_section("weights", a_.weights32);
      break;
    case WeightFormat::kFloat16:
      archive.add_section("weights", a_.weights16);
      break;
    case WeightFormat::kS8:
      archive.add_section("weights", a_.codes);
      archive.add_section("vertex_scales", a_.vertex_scales);
      break;
  }
  archive.add_section("representatives", a_.reps);
}

std::unique_ptr<CompressedTransfer> CpcaShTransfer::load(const ArchiveReader& r) {
  const auto fail = [&](const std::string& problem) {
    return InputError(r.path(), fmt::format("{}: {}", kName, problem));
  };
  const int version = r.meta_value<int>("cpca_sh_version");
  if (version != kStateVersion)
    throw fail(fmt::format(
        "state version {} is not the version {} this build reads{}", version, kStateVersion,
        version < kStateVersion ? " (older versions hold no local bin count, model error or "
                                  "signal; compress the transfer again)"
                                : ""));
  CpcaShArrays a;
  a.vertices = r.meta_value<std::size_t>("vertices");
  a.order = r.meta_value<int>("order");
  a.output_order = r.meta_value<int>("output_order");
  const auto clusters = r.meta_value<std::size_t>("clusters");
  a.signal_error = r.meta_value<double>("signal_error");
  a.local_count = r.meta_value<int>("local_count");
  a.frobenius_error = r.meta_value<double>("frobenius_error");
  a.signal_squared_error = r.meta_value<double>("signal_squared_error");
  a.signal_squared_norm = r.meta_value<double>("signal_squared_norm");
  try {
    a.signal = signal_from(r.meta_value<std::string>("signal"));
    a.projection = projection_from(r.meta_value<std::string>("projection"));
    a.metric = metric_from(r.meta_value<std::string>("metric"));
    a.method = method_from(r.meta_value<std::string>("method"));
    a.format = weight_format_from(r.meta_value<std::string>("weights"));
  } catch (const ParameterError& e) {
    throw fail(e.what());
  }
  if (a.order < 1 || a.order > kInputOrder || a.output_order < 1 || a.output_order > a.order ||
      clusters == 0 || clusters > std::max<std::size_t>(a.vertices, 1))
    throw fail(fmt::format("bad shape: order {}, output order {}, {} clusters for {} vertices",
                           a.order, a.output_order, clusters, a.vertices));
  if (!(std::isfinite(a.signal_error) && a.signal_error >= 0 && std::isfinite(a.frobenius_error) &&
        a.frobenius_error >= 0))
    throw fail("the signal or the model's Frobenius error is not a finite non-negative number");
  const int side = static_cast<int>(std::lround(std::sqrt(std::max(a.local_count, 0))));
  if (a.local_count < 1 || side * side != a.local_count)
    throw fail(fmt::format("local_count {} is no square grid S^2 >= 1", a.local_count));
  if (!(std::isfinite(a.signal_error) && a.signal_error >= 0) ||
      !(std::isfinite(a.signal_squared_error) && a.signal_squared_error >= 0) ||
      !(std::isfinite(a.signal_squared_norm) && a.signal_squared_norm >= 0))
    throw fail("a signal error or norm is not a finite non-negative number");
  if (a.signal == Signal::kDiffuse &&
      (a.output_order != 1 || a.projection != Projection::kZero || a.metric != Metric::kSphere))
    throw fail(fmt::format(
        "the diffuse signal has output order 1, zero projection and sphere metric, not {}, {}, {}",
        a.output_order, to_string(a.projection), to_string(a.metric)));
  constexpr std::uint64_t kU32 = std::numeric_limits<std::uint32_t>::max();
  if (a.vertices > kU32 / static_cast<std::uint64_t>(a.rows()))
    throw fail(fmt::format("{} vertices x {} output rows do not fit the relight's u32 index",
                           a.vertices, a.rows()));
  const auto counts = r.section<std::uint16_t>("vector_counts", clusters);
  a.first.assign(clusters + 1, 0);
  std::uint64_t reps = 0;
  for (std::size_t c = 0; c < clusters; ++c) {
    if (counts[c] > a.signal_dim())
      throw fail(
          fmt::format("cluster {} has {} vectors of dimension {}", c, counts[c], a.signal_dim()));
    reps += 1u + counts[c];
    if (reps > kU32) throw fail("the representative count overflows u32");
    a.first[c + 1] = static_cast<std::uint32_t>(reps);
  }
  a.ids = read_index_section(r, "cluster_ids", a.vertices, clusters);
  std::uint64_t weights = 0;
  for (std::uint32_t id : a.ids) weights += counts[id];
  switch (a.format) {
    case WeightFormat::kFloat32:
      a.weights32 = r.section<float>("weights", weights);
      break;
    case WeightFormat::kFloat16:
      a.weights16 = r.section<std::uint16_t>("weights", weights);
      break;
    case WeightFormat::kS8:
      a.codes = r.section<std::int8_t>("weights", weights);
      a.vertex_scales = r.section<float>("vertex_scales", a.vertices);
      break;
  }
  a.reps = r.section<float>("representatives",
                            static_cast<std::uint64_t>(a.first.back()) * a.signal_dim());
  const auto finite = [](float v) { return std::isfinite(v); };
  if (!std::all_of(a.reps.begin(), a.reps.end(), finite) ||
      !std::all_of(a.weights32.begin(), a.weights32.end(), finite) ||
      !std::all_of(a.vertex_scales.begin(), a.vertex_scales.end(), finite))
    throw fail("a representative, weight or vertex scale is not finite");
  try {
    derive_vertex_layout(a);
  } catch (const ParameterError& e) {
    throw fail(e.what());
  }
  if (!std::all_of(a.weight_values.begin(), a.weight_values.end(), finite))
    throw fail("a half weight is infinite or NaN");
  return std::make_unique<CpcaShTransfer>(std::move(a));
}

CompressorEntry registry_entry() {
  CompressorEntry e;
  e.name = std::string(kName);
  e.description =
      "clustered PCA of the per-vertex SH transfer matrices (Sloan et al. 2003), output side "
      "projected least-squares onto the hemisphere: per vertex a cluster id and n' weights, per "
      "cluster a mean and n' PCA matrices";
  e.params = {
      {"clusters", ParamType::kInt, "64", 1.0, 65536.0, {}, "clusters m_c (at most the vertices)"},
      {"vectors",
       ParamType::kInt,
       "8",
       0.0,
       256.0,
       {},
       "PCA vectors n' per cluster (adaptive: the budget is the bytes n' per cluster store, "
       "weights and vectors); 0 is pure VQ"},
      {"method",
       ParamType::kEnum,
       "iterative",
       std::nullopt,
       std::nullopt,
       {"static", "iterative", "adaptive"},
       "static = LBG VQ then PCA per cluster (section 4.1); iterative = classify by "
       "approximation error, PCA after every classification, vectors added one at a time "
       "(4.2); adaptive = iterative, then vectors redistributed by D_i^2 / (bytes of the "
       "vector's weights and its floats) under equal storage (4.3 with the cost model of 4.1)"},
      {"vq_iterations",
       ParamType::kInt,
       "20",
       0.0,
       1000.0,
       {},
       "Lloyd iterations of the LBG vector quantisation"},
      {"iterations_per_vector",
       ParamType::kInt,
       "10",
       0.0,
       1000.0,
       {},
       "classification + PCA passes for each added vector (the paper: 10-20)"},
      {"adaptive_iterations",
       ParamType::kInt,
       "5",
       0.0,
       1000.0,
       {},
       "redistribution passes of the adaptive method"},
      {"adaptive_max_vectors",
       ParamType::kInt,
       "0",
       0.0,
       1024.0,
       {},
       "most vectors one cluster may get (adaptive); 0: 4 n'"},
      {"weights",
       ParamType::kEnum,
       "float32",
       std::nullopt,
       std::nullopt,
       {"float32", "float16", "s8"},
       "precision of the per-vertex weights: f32, IEEE half, or s8 codes times a per-vertex f32 "
       "scale"},
      {"projection",
       ParamType::kEnum,
       "least_squares",
       std::nullopt,
       std::nullopt,
       {"zero", "least_squares"},
       "output side of M_p: zero = the zero-hemisphere projection as computed; least_squares = "
       "A^-1 M_p, the least-squares optimal projection onto the hemisphere (eq. (1), appendix 9)"},
      {"metric",
       ParamType::kEnum,
       "hemisphere",
       std::nullopt,
       std::nullopt,
       {"sphere", "hemisphere"},
       "norm CPCA minimises: sphere = the Euclidean norm of the SH matrices (the paper); "
       "hemisphere = the squared error over the upper hemisphere, where the output is used "
       "(CPCA of A^(1/2) X_p)"},
      {"order",
       ParamType::kInt,
       "5",
       1.0,
       static_cast<double>(kInputOrder),
       {},
       "SH order of the light (n = order^2 columns of M_p); the scene's SH transfer is computed "
       "at order 5 and cut to this order"},
      {"output_order",
       ParamType::kInt,
       "0",
       0.0,
       static_cast<double>(kInputOrder),
       {},
       "SH order of the transferred radiance (output_order^2 rows, e.g. 4 for the paper's 16 x "
       "25); 0: the same as order; at most order"},
      {"signal",
       ParamType::kEnum,
       "matrix",
       std::nullopt,
       std::nullopt,
       {"matrix", "diffuse"},
       "what is clustered per vertex: matrix = the output_order^2 x order^2 transfer matrix; "
       "diffuse = the paper's order^2-D shadowed diffuse transfer vector sqrt(4 pi / 3) M_p[2, :] "
       "(Fig. 2-4; projection, metric and output_order do not apply)"},
      {"adaptive_rule",
       ParamType::kEnum,
       "storage",
       std::nullopt,
       std::nullopt,
       {"storage", "sloan"},
       "adaptive redistribution: storage = D_i^2 / (bytes of the vector's weights and its "
       "floats) within what n' vectors per cluster store; sloan = the paper's D_i^2 / m_k until "
       "the per-vertex weights reach n' per vertex (section 4.3)"},
      {"pca_updates",
       ParamType::kEnum,
       "warm",
       std::nullopt,
       std::nullopt,
       {"warm", "converged"},
       "PCA after each classification: warm = one subspace iteration from the previous vectors "
       "(the last update converged); converged = every update to convergence (the paper's PCA "
       "per pass; the adaptive ranking reads converged D_i^2)"},
  };
  e.inputs.sh_order = kInputOrder;
  e.output_basis = RadianceBasis::kSphericalHarmonics;
  e.size_knob = SizeKnob{"vectors", SizeKnob::Direction::kLargerIsMoreStorage, 1.0, 32.0,
                         SizeKnob::Scale::kLinear};
  e.lossless = false;
  e.cost_hint_seconds = 65;  // where it was measured: docs/cli.md, "Cost hints"
  e.create = [](const ParamSet& p) -> std::unique_ptr<Compressor> {
    CpcaShParams c;
    c.options.clusters = static_cast<int>(p.get_int("clusters"));
    c.options.components = static_cast<int>(p.get_int("vectors"));
    c.options.method = p.get_enum<CpcaMethod>("method", {{"static", CpcaMethod::kStatic},
                                                         {"iterative", CpcaMethod::kIterative},
                                                         {"adaptive", CpcaMethod::kAdaptive}});
    c.options.vq_iterations = static_cast<int>(p.get_int("vq_iterations"));
    c.options.iterations_per_component = static_cast<int>(p.get_int("iterations_per_vector"));
    c.options.adaptive_iterations = static_cast<int>(p.get_int("adaptive_iterations"));
    c.options.adaptive_max_components = static_cast<int>(p.get_int("adaptive_max_vectors"));
    c.options.seed = static_cast<std::uint64_t>(p.get_int("seed"));
    c.format = p.get_enum<WeightFormat>("weights", {{"float32", WeightFormat::kFloat32},
                                                    {"float16", WeightFormat::kFloat16},
                                                    {"s8", WeightFormat::kS8}});
    c.options.adaptive_weight_cost = c.format == WeightFormat::kFloat32
                                         ? 1.0
                                         : (c.format == WeightFormat::kFloat16 ? 0.5 : 0.25);
    c.projection = p.get_enum<Projection>(
        "projection", {{"zero", Projection::kZero}, {"least_squares", Projection::kLeastSquares}});
    c.metric = p.get_enum<Metric>(
        "metric", {{"sphere", Metric::kSphere}, {"hemisphere", Metric::kHemisphere}});
    c.signal =
        p.get_enum<Signal>("signal", {{"matrix", Signal::kMatrix}, {"diffuse", Signal::kDiffuse}});
    c.options.adaptive_rule = p.get_enum<CpcaAdaptiveRule>(
        "adaptive_rule",
        {{"storage", CpcaAdaptiveRule::kStorage}, {"sloan", CpcaAdaptiveRule::kSloan}});
    c.options.converge_every_update =
        p.get_enum<bool>("pca_updates", {{"warm", false}, {"converged", true}});
    c.order = static_cast<int>(p.get_int("order"));
    const int output = static_cast<int>(p.get_int("output_order"));
    c.output_order = output == 0 ? c.order : output;
    if (c.signal == Signal::kDiffuse && c.order < 1)
      throw ParameterError(fmt::format("{}: signal = diffuse needs order >= 1", kName));
    if (c.signal == Signal::kMatrix && c.output_order > c.order)
      throw ParameterError(
          fmt::format("{}: output_order = {} exceeds order = {}", kName, c.output_order, c.order));
    return std::make_unique<CpcaShCompressor>(std::move(c));
  };
  e.load = &CpcaShTransfer::load;
  e.version = 3;
  return e;
}

PRT_REGISTER_COMPRESSOR(registry_entry);

}  // namespace prt::cpca_sh
