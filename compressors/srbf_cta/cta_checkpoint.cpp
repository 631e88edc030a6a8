#include "srbf_cta/cta_checkpoint.h"

#include <fmt/format.h>

#include <string>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/base/named_warning.h"
#include "prtlab/storage/stage_cache.h"

namespace prt::srbf_cta {
namespace {

constexpr const char* kKind = "srbf_cta-checkpoint";
constexpr std::uint32_t kVersion = 1;

template <class M>
void put_matrix(ArchiveWriter& w, nlohmann::json& shapes, const std::string& name, const M& m) {
  const Eigen::MatrixXd d = m;  // column-major copy
  shapes[name] = {d.rows(), d.cols()};
  w.add_section(name, std::vector<double>(d.data(), d.data() + d.size()));
}

template <class M>
M get_matrix(const ArchiveReader& r, const std::string& name) {
  const auto it = r.meta().find("shapes");
  if (it == r.meta().end() || !it->is_object())
    throw InputError(r.path(), "checkpoint: metadata 'shapes' missing or not an object");
  const nlohmann::json& shapes = *it;
  if (!shapes.contains(name) || !shapes[name].is_array() || shapes[name].size() != 2 ||
      !shapes[name][0].is_number_integer() || !shapes[name][1].is_number_integer())
    throw InputError(r.path(), "checkpoint: no shape for section '" + name + "'");
  const auto rows = shapes[name][0].get<std::int64_t>(), cols = shapes[name][1].get<std::int64_t>();
  if (rows < 0 || cols < 0) throw InputError(r.path(), "checkpoint: negative shape of " + name);
  const auto v = r.view<double>(name, static_cast<std::uint64_t>(rows * cols));
  return M(Eigen::Map<const Eigen::MatrixXd>(v.data(), rows, cols));
}

}  // namespace

Hash128 cta_checkpoint_key(const TensorView& t, const CtaOptions& o) {
  Hasher h;
  h.add(kKind).add(kVersion);
  h.add(static_cast<std::uint64_t>(t.vertices))
      .add(static_cast<std::uint64_t>(t.view))
      .add(static_cast<std::uint64_t>(t.light));
  h.add_array(t.values);
  h.add(o.clusters).add(o.rank_view).add(o.rank_light).add(o.rank_vertex);
  h.add(o.clustering_iterations)
      .add(o.clustering_tolerance)
      .add(o.hooi_sweeps)
      .add(o.seed)
      .add(o.elbg_rounds)
      .add(o.elbg_dims);
  return h.digest();
}

ArchiveWriter save_cta_checkpoint(const CtaCheckpoint& c) {
  const CtaModel& m = c.model;
  ArchiveWriter w(kKind, kVersion);
  nlohmann::json shapes = nlohmann::json::object();
  w.add_meta("view", m.view).add_meta("light", m.light);
  w.add_meta("rank_view", m.rank_view).add_meta("rank_light", m.rank_light);
  w.add_meta("rank_vertex", m.rank_vertex).add_meta("clusters", m.clusters.size());
  w.add_meta("clustering_iterations", m.clustering_iterations);
  w.add_meta("clustering_converged", c.clustering_converged);
  w.add_meta("total_squared_norm", m.total_squared_norm);
  w.add_meta("elbg_squared_error", m.elbg_squared_error);
  w.add_meta("initialisation_seconds", m.times.initialisation);
  w.add_meta("clustering_seconds", m.times.clustering);
  put_matrix(w, shapes, "view_basis", m.view_basis);
  put_matrix(w, shapes, "weights", m.weights);
  std::vector<double> errors;
  for (std::size_t k = 0; k < m.clusters.size(); ++k) {
    const CtaCluster& cl = m.clusters[k];
    put_matrix(w, shapes, fmt::format("light{}", k), cl.light);
    put_matrix(w, shapes, fmt::format("dual{}", k), cl.dual);
    put_matrix(w, shapes, fmt::format("uv{}", k), c.vertex_bases[k]);
    errors.push_back(cl.squared_error);
  }
  w.add_section("cluster_errors", std::move(errors));
  w.add_section("assignments", m.assignments);
  w.add_section("reclassification_errors", m.reclassification_errors);
  w.add_section("refit_errors", m.refit_errors);
  w.add_meta("shapes", shapes);
  return w;
}

CtaCheckpoint load_cta_checkpoint(const ArchiveReader& r) {
  r.expect_kind(kKind, kVersion);
  CtaCheckpoint c;
  CtaModel& m = c.model;
  m.view = r.meta_value<std::size_t>("view");
  m.light = r.meta_value<std::size_t>("light");
  m.rank_view = r.meta_value<int>("rank_view");
  m.rank_light = r.meta_value<int>("rank_light");
  m.rank_vertex = r.meta_value<int>("rank_vertex");
  const auto clusters = r.meta_value<std::size_t>("clusters");
  m.clustering_iterations = r.meta_value<int>("clustering_iterations");
  c.clustering_converged = r.meta_value<bool>("clustering_converged");
  m.total_squared_norm = r.meta_value<double>("total_squared_norm");
  m.elbg_squared_error = r.meta_value<double>("elbg_squared_error");
  m.times.initialisation = r.meta_value<double>("initialisation_seconds");
  m.times.clustering = r.meta_value<double>("clustering_seconds");
  m.view_basis = get_matrix<Eigen::MatrixXd>(r, "view_basis");
  m.weights = get_matrix<RowMajorMatrixXd>(r, "weights");
  m.assignments = r.section<std::uint32_t>("assignments", m.weights.rows());
  const std::vector<double> errors = r.section<double>("cluster_errors", clusters);
  m.clusters.resize(clusters);
  c.vertex_bases.resize(clusters);
  for (std::size_t k = 0; k < clusters; ++k) {
    m.clusters[k].light = get_matrix<Eigen::MatrixXd>(r, fmt::format("light{}", k));
    m.clusters[k].dual = get_matrix<RowMajorMatrixXd>(r, fmt::format("dual{}", k));
    c.vertex_bases[k] = get_matrix<Eigen::MatrixXd>(r, fmt::format("uv{}", k));
    m.clusters[k].squared_error = errors[k];
  }
  for (std::size_t x = 0; x < m.assignments.size(); ++x) {
    if (m.assignments[x] >= clusters)
      throw InputError(r.path(), fmt::format("checkpoint: vertex {} in cluster {} of {}", x,
                                             m.assignments[x], clusters));
    m.clusters[m.assignments[x]].members.push_back(static_cast<std::uint32_t>(x));
  }
  for (std::size_t k = 0; k < clusters; ++k)
    if (c.vertex_bases[k].rows() != static_cast<Eigen::Index>(m.clusters[k].members.size()) &&
        c.vertex_bases[k].size() != 0)
      throw InputError(r.path(),
                       fmt::format("checkpoint: cluster {}'s vertex basis has {} rows "
                                   "for {} members",
                                   k, c.vertex_bases[k].rows(), m.clusters[k].members.size()));
  m.reclassification_errors = r.section<double>("reclassification_errors");
  m.refit_errors = r.section<double>("refit_errors");
  return c;
}

std::filesystem::path cta_checkpoint_path(const Hash128& key) {
  return StageCache().path_for(kKind, key);
}

std::optional<CtaCheckpoint> read_cta_checkpoint(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return std::nullopt;
  try {
    return load_cta_checkpoint(ArchiveReader::open(path, kKind, kVersion));
  } catch (const InputError& e) {
    log_warn_named("srbf_cta-checkpoint-unusable", "{}: {}; starting from the beginning",
                   path.string(), e.what());
    return std::nullopt;
  }
}

}  // namespace prt::srbf_cta
