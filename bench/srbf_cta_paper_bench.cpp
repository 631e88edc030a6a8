// The paper's signal (Tsai and Shih 2006, Tables 1 and 2): T folded with a Cook-Torrance BRDF in
// K separable terms (transfer/brdf_weighted_transfer.h), compressed by srbf_cta (`signal=brdf`)
// and by an all-frequency CPCA in the layout of Table 2 (Liu et al. 2004 as the paper runs it),
// each reporting the SE ratio against the K-term signal, storage and time.
//
//   srbf_cta_paper_bench <scene> <out.json> <run>...
//
// A run is "srbf_cta:k=v,k=v" (any srbf_cta parameters; signal=brdf is implied),
// "cpca:k=v,..." (the registered cpca backend on the declared BRDF-weighted input, core
// compress/brdf_signal.h: Sloan's CPCA of the K folded rows of every vertex, relit through Phi;
// signal=brdf implied), or "afcpca:k=v,...". afcpca: the folded signal Psi T_x (K x N per vertex)
// projected onto one shared view basis U (K x rank_view, the top eigenvectors of sum_x T'_x
// T'_x^T), the pixels split into `segments` runs of N / segments consecutive pixels, and per
// segment a CPCA (core numeric/clustered_pca.h, iterative, `passes` classifications per component
// count) of every vertex's rank_view x (N / segments) block with `clusters` clusters and
// `components` weights; storage at 16 bits per value (means, components, weights) plus a cluster id
// per vertex and segment. Parameters: terms (16), rank_view (8), segments (24), clusters,
// components (12), passes (1), and the BRDF's brdf_diffuse / brdf_roughness / brdf_fresnel0
// (srbf_cta's defaults).
//
// The SE ratio is ||T~' - T'||_F^2 / ||T'||_F^2 with T' = Psi T the K-term signal in the pixel
// basis (the paper's "raw PRT data ... by setting the BRDF terms to 16"). Logged at info level.
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "prtlab/base/build_info.h"
#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/compress/backend_input.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/geometry/scene.h"
#include "prtlab/numeric/clustered_pca.h"
#include "prtlab/numeric/row_set.h"
#include "prtlab/storage/atomic_file.h"
#include "prtlab/storage/data_paths.h"
#include "prtlab/storage/stage_cache.h"
#include "prtlab/transfer/brdf_weighted_transfer.h"
#include "srbf_cta/srbf_cta.h"

namespace {

using Clock = std::chrono::steady_clock;
using Params = std::map<std::string, std::string>;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::pair<std::string, Params> parse_run(const std::string& run) {
  const auto colon = run.find(':');
  Params p;
  const std::string kind = run.substr(0, colon);
  if (colon != std::string::npos) {
    std::string rest = run.substr(colon + 1);
    std::size_t at = 0;
    while (at < rest.size()) {
      const std::size_t comma = rest.find(',', at);
      const std::string kv = rest.substr(at, comma == std::string::npos ? comma : comma - at);
      const auto eq = kv.find('=');
      if (eq == std::string::npos)
        throw prt::ParameterError(fmt::format("run '{}': '{}' is not key=value", run, kv));
      p[kv.substr(0, eq)] = kv.substr(eq + 1);
      if (comma == std::string::npos) break;
      at = comma + 1;
    }
  }
  return {kind, p};
}

double take(Params& p, const std::string& key, double fallback) {
  const auto it = p.find(key);
  if (it == p.end()) return fallback;
  const double v = std::stod(it->second);
  p.erase(it);
  return v;
}

prt::CookTorrance brdf_of(Params& p) {
  prt::CookTorrance ct;
  ct.diffuse = take(p, "brdf_diffuse", ct.diffuse);
  ct.roughness = take(p, "brdf_roughness", ct.roughness);
  ct.fresnel0 = take(p, "brdf_fresnel0", ct.fresnel0);
  ct.validate();
  return ct;
}

nlohmann::json run_srbf_cta(const prt::PreparedScene& scene, Params p) {
  p["signal"] = "brdf";
  const prt::TransferMatrix& t = scene.transfer.result.transfer;
  const auto t0 = Clock::now();
  const auto ct = prt::CompressorRegistry::instance()
                      .create("srbf_cta", p)
                      ->compress({t, nullptr, scene.cubemap, scene.grid}, prt::Progress::null());
  const double seconds = seconds_since(t0);
  const auto& a = dynamic_cast<const prt::srbf_cta::SrbfCtaTransfer&>(*ct).arrays();
  const double k = a.brdf_terms, v = static_cast<double>(a.vertices);
  nlohmann::json j;
  j["kind"] = "srbf_cta";
  j["params"] = p;
  j["vertices"] = a.vertices;
  j["clusters"] = a.clusters();
  j["ranks"] = {a.rank_view, a.rank_light, a.rank_vertex};
  j["brdf_terms"] = a.brdf_terms;
  j["srbfs"] = a.srbf_count;
  j["se_ratio_srbf"] = a.srbf_frobenius_error * a.srbf_frobenius_error;
  j["se_ratio_srbf_cta"] = a.frobenius_error * a.frobenius_error;
  j["storage_bytes"] = ct->storage().total_bytes();
  // The paper's accounting: raw = f32 dense K x N per vertex, SRBF data at 16 bits.
  j["raw_bytes"] = v * k * a.pixel_count * 4.0;
  j["srbf_bytes"] = v * k * a.srbf_count * 2.0;
  j["seconds"] = seconds;
  return j;
}

// Any registered backend that declares the BRDF-weighted input, through the run's preparation
// (so the folded rows are built once for the runs on one BRDF).
nlohmann::json run_backend(const prt::PreparedScene& scene, const std::string& name, Params p) {
  p["signal"] = "brdf";
  const prt::CompressorEntry& entry = prt::CompressorRegistry::instance().get(name);
  if (!entry.inputs.brdf_signal)
    throw prt::ParameterError(
        fmt::format("backend '{}' does not declare the BRDF-weighted signal", name));
  const auto compressor = prt::CompressorRegistry::instance().create(name, p);
  const auto t0 = Clock::now();
  const auto ct = compressor->compress(scene.input(entry), prt::Progress::null());
  const double seconds = seconds_since(t0);
  const prt::TransferMatrix& t = scene.transfer.result.transfer;
  const double e = ct->expected_frobenius_error().value_or(std::nan(""));
  nlohmann::json j;
  j["kind"] = name;
  j["params"] = p;
  j["vertices"] = t.vertex_count();
  j["brdf_terms"] = std::stoi(p.count("brdf_terms") ? p.at("brdf_terms") : "16");
  j["se_ratio"] = e * e;
  j["storage_bytes"] = ct->storage().total_bytes();
  j["storage"] = nlohmann::json::array();
  for (const auto& c : ct->storage().components)
    j["storage"].push_back({{"name", c.name}, {"bytes", c.bytes}});
  j["raw_bytes"] = static_cast<double>(t.vertex_count()) * j["brdf_terms"].get<int>() *
                   static_cast<double>(t.cols()) * 4.0;
  j["flops_per_relight"] = ct->flops_per_relight();
  j["seconds"] = seconds;
  return j;
}

nlohmann::json run_afcpca(const prt::PreparedScene& scene, Params p) {
  const prt::TransferMatrix& t = scene.transfer.result.transfer;
  const prt::CookTorrance brdf = brdf_of(p);
  const int terms = static_cast<int>(take(p, "terms", 16));
  const int rv = static_cast<int>(take(p, "rank_view", 8));
  const int segments = static_cast<int>(take(p, "segments", 24));
  const int clusters = static_cast<int>(take(p, "clusters", 9));
  const int components = static_cast<int>(take(p, "components", 12));
  const int passes = static_cast<int>(take(p, "passes", 1));
  if (!p.empty())
    throw prt::ParameterError(fmt::format("afcpca: unknown parameter '{}'", p.begin()->first));
  const int n = static_cast<int>(t.cols()), m = t.local_count();
  if (segments < 1 || n % segments != 0 || rv < 1 || rv > terms)
    throw prt::ParameterError(fmt::format(
        "afcpca: {} segments of {} pixels, or rank_view {} of {} terms", segments, n, rv, terms));
  const auto t0 = Clock::now();
  const prt::BrdfFold fold = prt::fold_brdf(scene.grid, brdf, terms);
  // sum_x T'_x T'_x^T = Psi diag(d) Psi^T: a vertex block's rows share no column.
  Eigen::VectorXd d = Eigen::VectorXd::Zero(m);
  for (std::size_t row = 0; row < t.rows(); ++row)
    for (std::uint32_t e = t.row_offsets()[row]; e < t.row_offsets()[row + 1]; ++e)
      d(static_cast<Eigen::Index>(row % static_cast<std::size_t>(m))) +=
          static_cast<double>(t.value(e)) * t.value(e);
  const Eigen::MatrixXd gram = fold.light * d.asDiagonal() * fold.light.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(gram);
  const Eigen::MatrixXd u = eig.eigenvectors().rightCols(rv).rowwise().reverse();  // K x rv
  const Eigen::MatrixXd w = u.transpose() * fold.light;  // rv x M: U^T Psi
  const double total_sq = prt::folded_squared_norm(t, fold);
  const double kept_sq = (w.colwise().squaredNorm().transpose().array() * d.array()).sum();
  const int seg = n / segments;
  const std::size_t vertices = t.vertex_count(), dims = static_cast<std::size_t>(rv) * seg;
  double cpca_sq = 0;
  double classify_s = 0;
  std::uint64_t values = 0, weights = 0;
  std::vector<double> block(vertices * dims);
  for (int s = 0; s < segments; ++s) {
    std::fill(block.begin(), block.end(), 0.0);
    const int lo = s * seg, hi = lo + seg;
    tbb::parallel_for(std::size_t{0}, vertices, [&](std::size_t x) {
      double* out = block.data() + x * dims;
      for (int j = 0; j < m; ++j) {
        const std::size_t row = x * static_cast<std::size_t>(m) + static_cast<std::size_t>(j);
        for (std::uint32_t e = t.row_offsets()[row]; e < t.row_offsets()[row + 1]; ++e) {
          const int col = static_cast<int>(t.column(e));
          if (col < lo || col >= hi) continue;
          for (int a = 0; a < rv; ++a)
            out[static_cast<std::size_t>(a) * seg + (col - lo)] += w(a, j) * t.value(e);
        }
      }
    });
    prt::ClusteredPcaOptions o;
    o.clusters = clusters;
    o.components = components;
    o.method = prt::CpcaMethod::kIterative;
    o.iterations_per_component = passes;
    o.seed = static_cast<std::uint64_t>(s) + 1;
    const prt::ClusteredPca model =
        prt::clustered_pca(prt::RowSet::dense(std::span<const double>(block), vertices, dims), o);
    cpca_sq += model.squared_error;
    classify_s += model.times.classify;
    for (const auto& c : model.clusters) values += (1 + static_cast<std::uint64_t>(c.k())) * dims;
    weights += model.weight_count();
    prt::log_info("afcpca: segment {} of {}: squared error {:.6g} of {:.6g}", s + 1, segments,
                  model.squared_error, model.total_squared_norm);
  }
  const double seconds = seconds_since(t0);
  const double se = (total_sq - kept_sq + cpca_sq) / total_sq;
  nlohmann::json j;
  j["kind"] = "afcpca";
  j["vertices"] = vertices;
  j["brdf_terms"] = terms;
  j["rank_view"] = rv;
  j["segments"] = segments;
  j["clusters"] = clusters;
  j["components"] = components;
  j["passes"] = passes;
  j["se_ratio_view_truncation"] = (total_sq - kept_sq) / total_sq;
  j["se_ratio"] = se;
  const std::uint64_t id_bytes = clusters <= 256 ? 1 : 2;
  j["storage_bytes"] = 2 * (values + weights) + static_cast<std::uint64_t>(terms) * rv * 2 +
                       vertices * static_cast<std::uint64_t>(segments) * id_bytes;
  j["raw_bytes"] = static_cast<double>(vertices) * terms * n * 4.0;
  j["seconds"] = seconds;
  j["classify_seconds"] = classify_s;
  return j;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s <scene> <out.json> <run>...\n", argv[0]);
    return 2;
  }
  try {
    prt::set_log_level(prt::LogLevel::kInfo);
    const prt::SceneDesc desc = prt::parse_scene(prt::resolve_scene(argv[1]));
    prt::StageCache cache;
    prt::BackendInputs needs;
    needs.brdf_signal = true;
    const prt::PreparedScene scene = prt::prepare_scene(desc, needs, cache);
    nlohmann::json out;
    const prt::BuildInfo& b = prt::build_info();
    out["scene"] = desc.name;
    out["git"] = b.git_hash;
    out["build_type"] = b.build_type;
    out["machine"] = prt::machine_description();
    out["vertices"] = scene.transfer.result.transfer.vertex_count();
    out["runs"] = nlohmann::json::array();
    for (int i = 3; i < argc; ++i) {
      auto [kind, params] = parse_run(argv[i]);
      prt::log_info("run {}: {}", i - 2, argv[i]);
      nlohmann::json j =
          kind == "srbf_cta" ? run_srbf_cta(scene, params)
          : kind == "afcpca" ? run_afcpca(scene, params)
          : kind == "cpca"
              ? run_backend(scene, kind, params)
              : throw prt::ParameterError(fmt::format(
                    "run '{}': kind '{}' is none of srbf_cta, cpca, afcpca", argv[i], kind));
      j["run"] = argv[i];
      prt::log_info("run {}: {}", i - 2, j.dump());
      out["runs"].push_back(std::move(j));
      prt::write_text_atomically(argv[2], out.dump(2) + "\n");
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
