#pragma once
// `prtlab experiment table1|table2`: regenerate the central paper's Table I / Table II, our
// numbers beside the paper's (docs/experiments.md). The table's backend is `bicluster` by
// default, the paper's method, but any registered backend (a plugin's too) fills the same
// columns: TableOptions::backend, and the timing reference TableOptions::reference.
//
// Per scene: the exact transfer T and what the two backends declare they need (prepare_scene),
// the backend's compression and the reference's (stage cache), then
//   nnz(T), MFLOPs = 2 nnz / 1e6 per colour channel, reduced MFLOPs = the bicluster's
//   flops_per_relight / 1e6, computation % = reduced / MFLOPs, dense data MB = vertices x M x N
//   bytes / 1e6, reduced MB = the bicluster's storage, data % = reduced / dense,
//   precomputation minutes = T's computation + the biclustering, each as measured when the stage
//   was computed (recorded in the cached archives, so a cache hit still reports it; mesh building
//   is not included), relight ms (median of `repeats`) in C++ and OpenCL for bicluster and
//   uncompressed, the error over the evaluation lights, and the lossless check
//   (lossless_check.h).
// Computing a table is separate from rendering it (table_report.h).
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "lossless_check.h"
#include "paper_numbers.h"
#include "provenance.h"
#include "prtlab/compress/compressor.h"
#include "prtlab/geometry/scene.h"

namespace prt {
class ClContext;
}

namespace prt::experiments {

/// The paper's backend, the default of TableOptions::backend.
inline constexpr const char* kTableBackend = "bicluster";
/// The default timing reference: the exact CSR product.
inline constexpr const char* kReferenceBackend = "uncompressed";

struct TableOptions {
  std::vector<std::string> scenes;      ///< empty: the table's scenes; else names or .toml paths
  std::string backend = kTableBackend;  ///< the backend the table measures (--backend)
  std::string reference = kReferenceBackend;  ///< the timing reference (--reference)
  std::map<std::string, std::string> params;  ///< the backend's parameters (--param k=v)
  bool force = false;                         ///< recompute T and the compressions
  int repeats = 20;                           ///< timed relights per backend (median)
  int evaluation_lights = 8;                  ///< error lights (backend_evaluation.h), 1..8
  LosslessOptions lossless;
  ClContext* device = nullptr;                      ///< OpenCL timings; null: C++ only
  std::optional<std::filesystem::path> cache_root;  ///< stage cache; default prt::cache_dir()
  bool show_progress_bars = true;                   ///< the stages' progress bars (stderr)
  std::string command_line;                         ///< recorded in the provenance
  /// A line per scene and stage ("[2/4] armor: biclustering ..."); the CLI prints to stderr.
  std::function<void(const std::string&)> on_progress;
};

struct TimingPair {
  double ms_cpp = 0;                ///< median C++ relight (light projection excluded)
  std::optional<double> ms_opencl;  ///< median kernel time; empty without a device or kernel
  std::optional<double> opencl_vs_cpp_rel_l2;
};

struct SceneRow {
  std::string scene;
  std::filesystem::path scene_file;
  std::size_t vertices = 0;
  int local_count = 0;  ///< M
  int pixel_count = 0;  ///< N
  int supersampling = 0;
  std::uint64_t nnz = 0;
  double nnz_millions = 0;
  double mflops = 0;
  double reduced_mflops = 0;
  double computation_percent = 0;
  std::uint64_t dense_bytes = 0;
  double dense_mb = 0;
  std::uint64_t reduced_bytes = 0;
  double reduced_mb = 0;
  double data_percent = 0;
  std::string backend;                    ///< the measured backend
  std::string reference;                  ///< the timing reference
  std::vector<StorageComponent> storage;  ///< the backend's components
  double transfer_seconds = 0;            ///< when T was computed
  double compress_seconds = 0;            ///< when the backend's compression ran
  double precompute_minutes = 0;
  bool transfer_cache_hit = false;
  bool compress_cache_hit = false;
  std::map<std::string, std::string> params;  ///< canonical parameters of the backend
  TimingPair subject;                         ///< the backend's relight times
  TimingPair reference_timing;                ///< the reference's
  double ms_project_light = 0;
  double rel_l2_error_mean = 0;  ///< the backend vs exact, over the evaluation lights
  double rel_l2_error_max = 0;
  double frobenius_rel_error = 0;  ///< ||T~ - T||_F / ||T||_F (transfer_error.h)
  double frobenius_rel_error_stderr = 0;
  double max_vertex_rel_error = 0;
  std::vector<std::string> evaluation_lights;
  LosslessCheck lossless;
  std::optional<PaperRow> paper;
};

struct TableResult {
  PaperTable table = PaperTable::kTable1;
  std::vector<SceneRow> rows;
  Provenance provenance;
  nlohmann::json parameters;  ///< everything that determined the numbers (seeds, repeats, ...)
};

/// The scenes a run would use (`names`, else the table's), parsed: throws InputError for an
/// unknown scene (listing the known ones) or a malformed scene file. Cheap; no stage runs.
std::vector<SceneDesc> resolve_table_scenes(PaperTable table,
                                            const std::vector<std::string>& names);

/// Run the experiment. Every scene name and the bicluster parameters are validated before any
/// stage runs (an unknown scene is an InputError listing the known ones). Writes nothing but
/// the stage cache: see write_table_files.
TableResult run_paper_table(PaperTable table, const TableOptions& options);

}  // namespace prt::experiments
