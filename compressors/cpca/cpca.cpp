#include "cpca/cpca.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/base/named_warning.h"
#include "prtlab/base/progress.h"
#include "prtlab/compress/brdf_signal.h"
#include "prtlab/numeric/float16.h"
#include "prtlab/storage/archive.h"
#include "prtlab/storage/index_section.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt::cpca {
namespace {

struct CpcaParams {
  ClusteredPcaOptions options;
  WeightFormat format = WeightFormat::kFloat32;
  BrdfSignalParams signal;
};

RowSet rows_of(const TransferMatrix& t) {
  if (t.narrow_columns()) {
    return RowSet::csr(t.cols(), t.row_offsets(), t.columns16(), t.counts(), t.scale());
  }
  return RowSet::csr(t.cols(), t.row_offsets(), t.columns32(), t.counts(), t.scale());
}

class CpcaCompressor final : public Compressor {
 public:
  explicit CpcaCompressor(CpcaParams p) : p_(std::move(p)) {}

  std::unique_ptr<CompressedTransfer> compress(const TransferInput& input,
                                               Progress& progress) const override {
    check_transfer_shape(input, kName);
    const TransferMatrix& t = input.transfer;
    // The BRDF signal's folded rows, shared with the run's other backends on the same BRDF.
    std::shared_ptr<const FoldedRows> folded;
    if (p_.signal.enabled) {
      Progress fold_progress(fmt::format("{}: folding T with the BRDF", kName),
                             static_cast<std::int64_t>(t.vertex_count()));
      folded = brdf_signal_rows(input, p_.signal, fold_progress);
      log_info("{}: BRDF-weighted signal, {} terms: {} rows, {:.1f} MiB of folded rows", kName,
               p_.signal.terms, folded->rows(), folded->memory_bytes() / 1048576.0);
    }
    const RowSet rows = folded ? folded->row_set() : rows_of(t);
    ClusteredPcaOptions o = p_.options;
    // A small transfer gets what it can hold: one row per cluster at most, and no more vectors
    // than the light has pixels (README, "Parameters").
    const std::size_t row_count = rows.rows();
    if (static_cast<std::size_t>(o.clusters) > std::max<std::size_t>(1, row_count))
      log_warn_named("cpca-clusters-clamped", "{}: clusters = {} for {} rows; using {}", kName,
                     o.clusters, row_count, std::max<std::size_t>(1, row_count));
    if (static_cast<std::size_t>(o.components) > t.cols())
      log_warn_named("cpca-vectors-clamped", "{}: vectors = {} for {} pixels; using {}", kName,
                     o.components, t.cols(), t.cols());
    o.clusters =
        static_cast<int>(std::min<std::size_t>(o.clusters, std::max<std::size_t>(1, row_count)));
    o.components = static_cast<int>(std::min<std::size_t>(o.components, t.cols()));
    if (row_count == 0) throw ParameterError(fmt::format("{}: the transfer has no rows", kName));
    // The bar advances by passes: the planned count (a stage that converges early skips ahead).
    const std::int64_t planned =
        2 + (o.method == CpcaMethod::kStatic
                 ? 0
                 : std::int64_t{o.components} * o.iterations_per_component +
                       (o.method == CpcaMethod::kAdaptive ? o.adaptive_iterations : 0));
    std::int64_t passes = 0;
    const auto rows_total = static_cast<std::int64_t>(t.rows());  // the caller's bar counts T's
    o.on_pass = [&](const CpcaPass& pass) {
      log_debug("{}: {} pass {} ({} vectors): squared error {:.6g}, {} rows moved", kName,
                pass.stage, pass.iteration, pass.components, pass.squared_error, pass.reassigned);
      const std::int64_t before = rows_total * passes / planned;
      passes = std::min(planned, passes + 1);
      progress.advance(rows_total * passes / planned - before);
    };
    const ClusteredPca model = clustered_pca(rows, o);
    const CpcaPhaseTimes& tm = model.times;
    log_debug(
        "{}: {} clusters, {} weights; vq {:.2f} s, classify {:.2f} s ({} passes, {:.1f} GFLOP/s), "
        "pca {:.2f} s ({} updates), weights {:.2f} s",
        kName, model.clusters.size(), model.weight_count(), tm.vq, tm.classify, tm.classify_passes,
        tm.classify > 0 ? tm.classify_flops / tm.classify * 1e-9 : 0.0, tm.pca, tm.pca_updates,
        tm.weights);
    CpcaArrays a = encode(model, rows, t.vertex_count(), t.local_count(),
                          static_cast<int>(t.cols()), p_.options.method, p_.format);
    if (folded) {
      const Eigen::MatrixXd& phi = folded->fold.view;
      a.view_terms = p_.signal.terms;
      a.view.resize(static_cast<std::size_t>(phi.size()));
      for (Eigen::Index i = 0; i < phi.rows(); ++i)
        for (Eigen::Index k = 0; k < phi.cols(); ++k)
          a.view[static_cast<std::size_t>(i * phi.cols() + k)] = static_cast<float>(phi(i, k));
    }
    auto out = std::make_unique<CpcaTransfer>(std::move(a));
    progress.finish();
    return out;
  }

 private:
  CpcaParams p_;
};

}  // namespace

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

WeightFormat weight_format_from(std::string_view name) {
  for (WeightFormat f : {WeightFormat::kFloat32, WeightFormat::kFloat16, WeightFormat::kS8})
    if (to_string(f) == name) return f;
  throw ParameterError(
      fmt::format("{}: weight format '{}' is none of float32, float16, s8", kName, name));
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

namespace {
CpcaMethod method_from(std::string_view name) {
  for (CpcaMethod m : {CpcaMethod::kStatic, CpcaMethod::kIterative, CpcaMethod::kAdaptive})
    if (to_string(m) == name) return m;
  throw ParameterError(
      fmt::format("{}: method '{}' is none of static, iterative, adaptive", kName, name));
}
}  // namespace

std::size_t CpcaArrays::id_bytes() const {
  return index_bytes(clusters());
}

int CpcaArrays::uniform_vectors() const {
  if (clusters() == 0) return -1;
  const int k = vectors_of(0);
  for (std::size_t c = 1; c < clusters(); ++c)
    if (vectors_of(c) != k) return -1;
  return k;
}

void derive_row_layout(CpcaArrays& a) {
  const std::size_t rows = a.rows();
  a.weight_offsets.assign(rows + 1, 0);
  std::uint64_t total = 0;
  for (std::size_t r = 0; r < rows; ++r) {
    total += static_cast<std::uint64_t>(a.vectors_of(a.ids[r]));
    if (total > std::numeric_limits<std::uint32_t>::max()) {
      throw ParameterError(
          fmt::format("{}: {} weights exceed the u32 offsets of the relight", kName, total));
    }
    a.weight_offsets[r + 1] = static_cast<std::uint32_t>(total);
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

CpcaArrays encode(const ClusteredPca& model, const RowSet& rows, std::size_t vertices,
                  int local_count, int pixel_count, CpcaMethod method, WeightFormat format) {
  CpcaArrays a;
  a.vertices = vertices;
  a.local_count = local_count;
  a.pixel_count = pixel_count;
  a.method = method;
  a.format = format;
  const auto n = static_cast<std::size_t>(pixel_count);
  a.first.assign(model.clusters.size() + 1, 0);
  for (std::size_t c = 0; c < model.clusters.size(); ++c) {
    a.first[c + 1] = a.first[c] + 1 + static_cast<std::uint32_t>(model.clusters[c].k());
  }
  a.reps.resize(static_cast<std::size_t>(a.first.back()) * n);
  for (std::size_t c = 0; c < model.clusters.size(); ++c) {
    const CpcaCluster& cl = model.clusters[c];
    float* rep = a.reps.data() + static_cast<std::size_t>(a.first[c]) * n;
    for (std::size_t j = 0; j < n; ++j)
      rep[j] = static_cast<float>(cl.mean[static_cast<Eigen::Index>(j)]);
    for (int i = 0; i < cl.k(); ++i) {
      float* v = rep + static_cast<std::size_t>(i + 1) * n;
      for (std::size_t j = 0; j < n; ++j)
        v[j] = static_cast<float>(cl.components(static_cast<Eigen::Index>(j), i));
    }
  }
  a.ids = model.assignments;
  const std::size_t total = model.weights.size();
  switch (format) {
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
      a.row_scales.resize(a.rows());
      for (std::size_t r = 0; r < a.rows(); ++r) {
        const std::uint64_t b = model.weight_offsets[r], e = model.weight_offsets[r + 1];
        double top = 0.0;
        for (std::uint64_t i = b; i < e; ++i) top = std::max(top, std::abs(model.weights[i]));
        float scale = static_cast<float>(top / 127.0);
        // A weight range below float's smallest normal (or zero) keeps scale 1: all codes 0.
        if (!(scale >= std::numeric_limits<float>::min()) || !std::isfinite(scale)) scale = 1.0f;
        a.row_scales[r] = scale;
        for (std::uint64_t i = b; i < e; ++i) {
          const double q = std::nearbyint(model.weights[i] / static_cast<double>(scale));
          a.codes[i] = static_cast<std::int8_t>(std::clamp(q, -127.0, 127.0));
        }
      }
      break;
    }
  }
  derive_row_layout(a);
  // The error of the model as stored: f32 representatives, the weights as the relight reads
  // them (s8 codes times the row's scale).
  RowMajorMatrixXd reps(static_cast<Eigen::Index>(a.first.back()), static_cast<Eigen::Index>(n));
  for (Eigen::Index r = 0; r < reps.rows(); ++r)
    for (Eigen::Index j = 0; j < reps.cols(); ++j)
      reps(r, j) = a.reps[static_cast<std::size_t>(r) * n + static_cast<std::size_t>(j)];
  std::vector<double> w(a.weight_values.size());
  for (std::size_t r = 0; r < a.rows(); ++r) {
    const double scale = format == WeightFormat::kS8 ? a.row_scales[r] : 1.0;
    for (std::uint32_t i = a.weight_offsets[r]; i < a.weight_offsets[r + 1]; ++i)
      w[i] = static_cast<double>(a.weight_values[i]) * scale;
  }
  std::vector<std::uint64_t> offsets(a.weight_offsets.begin(), a.weight_offsets.end());
  const double se = affine_codebook_squared_error(rows, a.ids, reps, a.first, w, offsets);
  a.frobenius_error = model.total_squared_norm > 0 ? std::sqrt(se / model.total_squared_norm) : 0.0;
  return a;
}

StorageReport CpcaTransfer::storage() const {
  StorageReport r;
  const std::uint64_t rows = a_.rows();
  r.components.push_back({"cluster_ids", rows * a_.id_bytes(),
                          fmt::format("u{} per row (vertex * {}): its cluster", 8 * a_.id_bytes(),
                                      a_.view_terms > 0 ? "K + BRDF term" : "M + cell")});
  const std::uint64_t w = a_.weight_values.size();
  switch (a_.format) {
    case WeightFormat::kFloat32:
      r.components.push_back({"weights", w * 4, "f32 per row and vector of its cluster: w_i"});
      break;
    case WeightFormat::kFloat16:
      r.components.push_back(
          {"weights", w * 2, "IEEE half per row and vector of its cluster: w_i, nearest even"});
      break;
    case WeightFormat::kS8:
      r.components.push_back(
          {"weights", w, "s8 code q per row and vector: w_i = q * the row's scale, |q| <= 127"});
      r.components.push_back(
          {"row_scales", rows * 4, "f32 per row: max |w_i| / 127 (the value of q = 1)"});
      break;
  }
  r.components.push_back(
      {"representatives", a_.reps.size() * std::uint64_t{4},
       "f32 N-vector per cluster mean and per cluster vector, cluster after cluster"});
  if (a_.uniform_vectors() < 0) {
    r.components.push_back(
        {"vector_counts", a_.clusters() * std::uint64_t{2}, "u16 per cluster: its k_c (adaptive)"});
  }
  if (a_.view_terms > 0)
    r.components.push_back({"view", a_.view.size() * std::uint64_t{4},
                            "f32 M x K: the BRDF's view factor Phi (signal=brdf)"});
  return r;
}

double CpcaTransfer::flops_per_relight() const {
  const double per_rep = 2.0 * a_.pixel_count;
  const double blend = 2.0 * static_cast<double>(a_.weight_values.size()) +
                       (a_.format == WeightFormat::kS8 ? static_cast<double>(a_.rows()) : 0.0);
  const double view = 2.0 * static_cast<double>(a_.vertices) * static_cast<double>(a_.view.size());
  return per_rep * static_cast<double>(a_.rep_count()) + blend + view;
}

LightCoeffs CpcaTransfer::project_light(const Cubemap& radiance) const {
  return pixel_light(radiance, static_cast<std::size_t>(a_.pixel_count), kName);
}

void CpcaTransfer::relight(const LightCoeffs& light, LocalRadiance& out) const {
  check_pixel_light(light, static_cast<std::size_t>(a_.pixel_count), kName);
  out.ensure_shape(RadianceBasis::kPixel, a_.local_count, a_.vertices);
  const std::vector<Rgb> q = representative_dots(a_, light.values);
  if (a_.view_terms == 0) {
    blend_rows(a_, q, out.values);
    return;
  }
  std::vector<Rgb> terms(a_.rows());
  blend_rows(a_, q, terms);
  apply_view(a_, terms, out.values);
}

void CpcaTransfer::relight_vertices(const LightCoeffs& light,
                                    std::span<const std::uint32_t> vertices,
                                    LocalRadiance& out) const {
  check_pixel_light(light, static_cast<std::size_t>(a_.pixel_count), kName);
  check_vertex_subset(vertices, a_.vertices, kName);
  if (a_.view_terms > 0) return relight(light, out);
  out.ensure_shape(RadianceBasis::kPixel, a_.local_count, a_.vertices);
  const std::vector<Rgb> q = representative_dots(a_, light.values);
  blend_vertex_rows(a_, q, vertices, out.values);
}

std::unique_ptr<DeviceRelighter> CpcaTransfer::upload(ClContext& context, const ParamSet&) const {
  return upload_cpca(context, a_);
}

void CpcaTransfer::save(ArchiveWriter& archive) const {
  archive.add_meta("cpca_version", kStateVersion);
  archive.add_meta("vertices", a_.vertices);
  archive.add_meta("local_count", a_.local_count);
  archive.add_meta("pixel_count", a_.pixel_count);
  archive.add_meta("clusters", a_.clusters());
  archive.add_meta("method", std::string(to_string(a_.method)));
  archive.add_meta("weights", std::string(to_string(a_.format)));
  archive.add_meta("frobenius_error", a_.frobenius_error);
  archive.add_meta("view_terms", a_.view_terms);
  if (a_.view_terms > 0) archive.add_section("view", a_.view);
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
      archive.add_section("row_scales", a_.row_scales);
      break;
  }
  archive.add_section("representatives", a_.reps);
}

std::unique_ptr<CompressedTransfer> CpcaTransfer::load(const ArchiveReader& r) {
  const auto fail = [&](const std::string& problem) {
    return InputError(r.path(), fmt::format("{}: {}", kName, problem));
  };
  const int version = r.meta_value<int>("cpca_version");
  if (version != kStateVersion)
    throw fail(fmt::format("state version {} is not the version {} this build reads", version,
                           kStateVersion));
  CpcaArrays a;
  a.vertices = r.meta_value<std::size_t>("vertices");
  a.local_count = r.meta_value<int>("local_count");
  a.pixel_count = r.meta_value<int>("pixel_count");
  const auto clusters = r.meta_value<std::size_t>("clusters");
  a.frobenius_error = r.meta_value<double>("frobenius_error");
  a.view_terms = r.meta_value<int>("view_terms");
  try {
    a.method = method_from(r.meta_value<std::string>("method"));
    a.format = weight_format_from(r.meta_value<std::string>("weights"));
  } catch (const ParameterError& e) {
    throw fail(e.what());
  }
  if (a.local_count <= 0 || a.pixel_count <= 0 || clusters == 0)
    throw fail(fmt::format("bad shape: M = {}, N = {}, {} clusters", a.local_count, a.pixel_count,
                           clusters));
  if (a.view_terms < 0 || a.view_terms > a.local_count)
    throw fail(fmt::format("{} BRDF terms for M = {} (0 to M)", a.view_terms, a.local_count));
  if (!(std::isfinite(a.frobenius_error) && a.frobenius_error >= 0))
    throw fail("the Frobenius error is not a finite non-negative number");
  // Sizes the kernels index with u32, checked before anything is multiplied or allocated.
  constexpr std::uint64_t kU32 = std::numeric_limits<std::uint32_t>::max();
  if (a.vertices == 0 || a.vertices > kU32 / static_cast<std::uint64_t>(a.local_count))
    throw fail(fmt::format("{} vertices x M = {} rows do not fit the relight's u32 row index",
                           a.vertices, a.local_count));
  const std::uint64_t rows = a.vertices * static_cast<std::uint64_t>(a.rows_per_vertex());
  if (a.view_terms > 0)
    a.view = r.section<float>("view", static_cast<std::uint64_t>(a.local_count) * a.view_terms);
  if (clusters > rows) throw fail(fmt::format("{} clusters for {} rows", clusters, rows));
  const auto counts = r.section<std::uint16_t>("vector_counts", clusters);
  a.first.assign(clusters + 1, 0);
  std::uint64_t reps = 0;
  for (std::size_t c = 0; c < clusters; ++c) {
    if (counts[c] > a.pixel_count)
      throw fail(
          fmt::format("cluster {} has {} vectors of dimension {}", c, counts[c], a.pixel_count));
    reps += 1u + counts[c];
    if (reps > kU32) throw fail("the representative count overflows u32");
    a.first[c + 1] = static_cast<std::uint32_t>(reps);
  }
  a.ids = read_index_section(r, "cluster_ids", rows, clusters);
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
      a.row_scales = r.section<float>("row_scales", rows);
      break;
  }
  a.reps = r.section<float>("representatives",
                            static_cast<std::uint64_t>(a.first.back()) * a.pixel_count);
  const auto finite = [](float v) { return std::isfinite(v); };
  if (!std::all_of(a.reps.begin(), a.reps.end(), finite) ||
      !std::all_of(a.weights32.begin(), a.weights32.end(), finite) ||
      !std::all_of(a.row_scales.begin(), a.row_scales.end(), finite) ||
      !std::all_of(a.view.begin(), a.view.end(), finite))
    throw fail("a representative, weight, row scale or view factor is not finite");
  try {
    derive_row_layout(a);
  } catch (const ParameterError& e) {
    throw fail(e.what());
  }
  if (!std::all_of(a.weight_values.begin(), a.weight_values.end(), finite))
    throw fail("a half weight is infinite or NaN");
  return std::make_unique<CpcaTransfer>(std::move(a));
}

CompressorEntry registry_entry() {
  CompressorEntry e;
  e.name = std::string(kName);
  e.description =
      "clustered PCA of T's rows (Sloan et al. 2003): per row a cluster id and n' weights, per "
      "cluster a mean and n' PCA vectors; static, iterative or adaptive";
  e.params = {
      {"clusters", ParamType::kInt, "32", 1.0, 65536.0, {}, "clusters m_c"},
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
       "vector's weights and its N floats) under equal storage (4.3 with the cost model of 4.1)"},
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
       "precision of the per-row weights: f32, IEEE half, or s8 codes times a per-row f32 scale"},
  };
  e.size_knob = SizeKnob{"vectors", SizeKnob::Direction::kLargerIsMoreStorage, 1.0, 16.0,
                         SizeKnob::Scale::kLinear};
  e.inputs.brdf_signal = true;
  e.lossless = false;
  e.cost_hint_seconds = 59;  // where it was measured: docs/cli.md, "Cost hints"
  e.create = [](const ParamSet& p) -> std::unique_ptr<Compressor> {
    CpcaParams c;
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
    c.signal = brdf_signal_params(p);
    c.format = p.get_enum<WeightFormat>("weights", {{"float32", WeightFormat::kFloat32},
                                                    {"float16", WeightFormat::kFloat16},
                                                    {"s8", WeightFormat::kS8}});
    // A stored weight against a stored representative value (f32), for the adaptive budget.
    c.options.adaptive_weight_cost = c.format == WeightFormat::kFloat32
                                         ? 1.0
                                         : (c.format == WeightFormat::kFloat16 ? 0.5 : 0.25);
    return std::make_unique<CpcaCompressor>(std::move(c));
  };
  e.load = &CpcaTransfer::load;
  e.version = 4;
  e.published = {
      {"chair",
       {{"clusters", "32"}, {"vectors", "8"}},
       "32 clusters x 8 PCA vectors: 36.2 MB, more than 10 hours to compress, severe artifacts",
       "Sun et al. 2008, Fig. 6; their chair has 16K vertices x 64 local directions"},
  };
  return e;
}

PRT_REGISTER_COMPRESSOR(registry_entry);

}  // namespace prt::cpca
