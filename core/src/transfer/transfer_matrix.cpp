#include "prtlab/transfer/transfer_matrix.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>

#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/base/progress.h"
#include "prtlab/base/statistics.h"
#include "prtlab/sphere/cubemap.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/transfer/visibility.h"

namespace prt {

// ---------------------------------------------------------------------------------------------
// TransferMatrix

double TransferMatrix::at(std::size_t row, std::uint32_t col) const {
  PRT_CHECK(row < rows(), "transfer row {} out of range ({})", row, rows());
  std::size_t lo = row_offsets_[row], hi = row_offsets_[row + 1];
  while (lo < hi) {
    const std::size_t mid = lo + (hi - lo) / 2;
    const std::uint32_t c = column(mid);
    if (c == col) return counts_[mid] * scale();
    if (c < col) {
      lo = mid + 1;
    } else {
      hi = mid;
    }
  }
  return 0.0;
}

std::uint64_t TransferMatrix::memory_bytes() const {
  return row_offsets_.size() * sizeof(std::uint32_t) + cols16_.size() * sizeof(std::uint16_t) +
         cols32_.size() * sizeof(std::uint32_t) + counts_.size();
}

// Appends per-point blocks in order into one CSR matrix.
class TransferAssembler {
 public:
  TransferAssembler(std::size_t vertices, int m, int n, int s) {
    t_.vertices_ = vertices;
    t_.m_ = m;
    t_.n_ = n;
    t_.s_ = s;
    t_.narrow_ = n <= 65536;
    t_.row_offsets_.clear();
    t_.row_offsets_.reserve(vertices * static_cast<std::size_t>(m) + 1);
    t_.row_offsets_.push_back(0);
  }

  void reserve(std::size_t nnz) {
    if (t_.narrow_) {
      t_.cols16_.reserve(nnz);
    } else {
      t_.cols32_.reserve(nnz);
    }
    t_.counts_.reserve(nnz);
  }

  /// One point's block: per-row entry counts (M), then columns and counts in row order.
  void append(std::span<const std::uint32_t> row_nnz, std::span<const std::uint32_t> cols,
              std::span<const std::uint8_t> counts) {
    PRT_CHECK(row_nnz.size() == static_cast<std::size_t>(t_.m_), "block has {} rows, M = {}",
              row_nnz.size(), t_.m_);
    const std::uint64_t total = static_cast<std::uint64_t>(t_.counts_.size()) + counts.size();
    if (total > std::numeric_limits<std::uint32_t>::max()) {
      throw ParameterError(
          fmt::format("the transfer matrix would have more than 2^32 - 1 non-zeros (32-bit row "
                      "offsets); use fewer "
                      "vertices, a smaller cubemap or a smaller local grid"));
    }
    std::uint32_t offset = t_.row_offsets_.back();
    for (std::uint32_t c : row_nnz) t_.row_offsets_.push_back(offset += c);
    if (t_.narrow_) {
      for (std::uint32_t c : cols) t_.cols16_.push_back(static_cast<std::uint16_t>(c));
    } else {
      t_.cols32_.insert(t_.cols32_.end(), cols.begin(), cols.end());
    }
    t_.counts_.insert(t_.counts_.end(), counts.begin(), counts.end());
  }

  TransferMatrix finish() {
    PRT_CHECK(t_.row_offsets_.size() == t_.rows() + 1, "assembled {} rows, expected {}",
              t_.row_offsets_.size() - 1, t_.rows());
    t_.cols16_.shrink_to_fit();
    t_.cols32_.shrink_to_fit();
    t_.counts_.shrink_to_fit();
    return std::move(t_);
  }

 private:
  TransferMatrix t_;
};

TransferMatrix TransferMatrix::from_csr(std::size_t vertices, int local_count, int pixel_count,
                                        int supersampling, std::vector<std::uint32_t> row_offsets,
                                        std::span<const std::uint32_t> columns,
                                        std::vector<std::uint8_t> counts) {
  auto fail = [](const std::string& what) { throw ParameterError("transfer matrix: " + what); };
  if (local_count < 1) fail(fmt::format("M = {} must be positive", local_count));
  if (pixel_count < 1) fail(fmt::format("N = {} must be positive", pixel_count));
  if (supersampling < 1 || supersampling > 15)
    fail(fmt::format("supersampling {} outside [1, 15]", supersampling));
  const std::size_t rows = vertices * static_cast<std::size_t>(local_count);
  if (row_offsets.size() != rows + 1) {
    fail(fmt::format("{} row offsets for {} rows (expected rows + 1)", row_offsets.size(), rows));
  }
  if (columns.size() != counts.size()) {
    fail(fmt::format("{} column indices but {} values", columns.size(), counts.size()));
  }
  if (row_offsets.front() != 0 || row_offsets.back() != counts.size()) {
    fail(fmt::format("row offsets run from {} to {}, expected 0 to nnz = {}", row_offsets.front(),
                     row_offsets.back(), counts.size()));
  }
  const int max_count = supersampling * supersampling;
  std::vector<std::uint32_t> seen(static_cast<std::size_t>(pixel_count),
                                  0);  // last vertex + 1 using column
  for (std::size_t row = 0; row < rows; ++row) {
    const std::uint32_t b = row_offsets[row], e = row_offsets[row + 1];
    if (e < b) fail(fmt::format("row offsets decrease at row {}", row));
    const auto vertex_tag = static_cast<std::uint32_t>(row / local_count + 1);
    for (std::uint32_t i = b; i < e; ++i) {
      if (columns[i] >= static_cast<std::uint32_t>(pixel_count)) {
        fail(fmt::format("row {}: column {} >= N = {}", row, columns[i], pixel_count));
      }
      if (i > b && columns[i] <= columns[i - 1])
        fail(fmt::format("row {}: columns not strictly increasing", row));
      if (counts[i] < 1 || counts[i] > max_count) {
        fail(fmt::format("row {}: count {} outside 1..{}", row, counts[i], max_count));
      }
      if (seen[columns[i]] == vertex_tag) {
        fail(fmt::format("vertex {}: column {} has more than one non-zero", row / local_count,
                         columns[i]));
      }
      seen[columns[i]] = vertex_tag;
    }
  }
  TransferAssembler assembler(vertices, local_count, pixel_count, supersampling);
  assembler.reserve(counts.size());
  // Re-append vertex by vertex: the assembler owns the narrowing rule.
  std::vector<std::uint32_t> row_nnz(static_cast<std::size_t>(local_count));
  for (std::size_t v = 0; v < vertices; ++v) {
    const std::size_t r0 = v * static_cast<std::size_t>(local_count);
    for (int j = 0; j < local_count; ++j)
      row_nnz[j] = row_offsets[r0 + j + 1] - row_offsets[r0 + j];
    const std::size_t b = row_offsets[r0], e = row_offsets[r0 + local_count];
    assembler.append(row_nnz, columns.subspan(b, e - b),
                     std::span<const std::uint8_t>(counts).subspan(b, e - b));
  }
  return assembler.finish();
}

// ---------------------------------------------------------------------------------------------
// CellLookup

namespace {
constexpr std::uint8_t kDefer = 255;
constexpr int kBelow = -2;
}  // namespace

CellLookup::CellLookup(const HemisphereGrid& grid, int resolution) : grid_(&grid), q_(resolution) {
  PRT_CHECK(resolution >= 4, "cell lookup resolution {} too small", resolution);
  const int q = q_;
  table_.assign(static_cast<std::size_t>(6) * q * q, kDefer);
  // With M >= 255 every lookup defers (cells would not fit the byte table).
  if (grid.cell_count() >= kDefer) {
    deferred_ = 1.0;
    return;
  }
  std::vector<int> corner(static_cast<std::size_t>(q + 1) * (q + 1));
  std::size_t upper = 0, deferred = 0;
  for (int face = 0; face < 5; ++face) {  // face 5 (-z) is wholly below the horizon
    tbb::parallel_for(0, q + 1, [&](int j) {
      for (int i = 0; i <= q; ++i) {
        const Vec3d d = CubemapLayout::face_direction(face, 2.0 * i / q - 1.0, 2.0 * j / q - 1.0);
        corner[static_cast<std::size_t>(j) * (q + 1) + i] = d.z > 0.0 ? grid.cell_of(d) : kBelow;
      }
    });
    for (int j = 0; j < q; ++j) {
      for (int i = 0; i < q; ++i) {
        const int c = corner[static_cast<std::size_t>(j) * (q + 1) + i];
        if (c == kBelow) continue;  // not an upper-hemisphere texel
        ++upper;
        bool same = i >= 1 && j >= 1 && i + 2 <= q && j + 2 <= q;
        for (int jj = j - 1; same && jj <= j + 2; ++jj)
          for (int ii = i - 1; same && ii <= i + 2; ++ii)
            same = corner[static_cast<std::size_t>(jj) * (q + 1) + ii] == c;
        if (same) {
          table_[(static_cast<std::size_t>(face) * q + j) * q + i] = static_cast<std::uint8_t>(c);
        } else {
          ++deferred;
        }
      }
    }
  }
  deferred_ = upper ? static_cast<double>(deferred) / static_cast<double>(upper) : 1.0;
}

int CellLookup::cell_of(const Vec3d& l) const {
  int face;
  double s, t;
  CubemapLayout::face_coords(l, face, s, t);
  const int i = std::clamp(static_cast<int>((s + 1.0) * 0.5 * q_), 0, q_ - 1);
  const int j = std::clamp(static_cast<int>((t + 1.0) * 0.5 * q_), 0, q_ - 1);
  const std::uint8_t c = table_[(static_cast<std::size_t>(face) * q_ + j) * q_ + i];
  if (c == kDefer) return grid_->cell_of(l);
  PRT_DCHECK(c == grid_->cell_of(l), "cell lookup disagrees with cell_of at ({}, {}, {})", l.x, l.y,
             l.z);
  return c;
}

// ---------------------------------------------------------------------------------------------
// compute_transfer

namespace {

// Local z given to a pixel centre on or below the tangent plane that still has unblocked
// sub-rays: it lands in the rim cell at its azimuth (see transfer_matrix.h).
constexpr double kLiftZ = 1e-9;

// Points per assembly batch: bounds the memory held in per-point blocks.
constexpr std::size_t kBatch = 1024;

struct PointBlock {
  std::vector<std::uint32_t> row_nnz;
  std::vector<std::uint32_t> cols;
  std::vector<std::uint8_t> counts;
};

struct ThreadScratch {
  std::vector<std::uint8_t> vis;
  std::vector<std::uint32_t> unblocked;
  std::vector<std::uint32_t> entry_col;
  std::vector<std::uint8_t> entry_count;
  std::vector<std::uint16_t> entry_cell;
  std::vector<std::uint32_t> cursor;
  ShTransferIntegrator::Scratch sh;
};

// CPU time of the calling thread: phase times stay meaningful on a loaded machine, where
// wall-clock per thread would include time spent preempted.
std::int64_t thread_cpu_ns() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace

std::vector<SurfacePoint> vertex_points(const Mesh& mesh) {
  if (mesh.normals.size() != mesh.vertex_count()) {
    throw ParameterError(fmt::format(
        "compute_transfer: the mesh has {} normals for {} vertices (compute normals first)",
        mesh.normals.size(), mesh.vertex_count()));
  }
  std::vector<SurfacePoint> points(mesh.vertex_count());
  for (std::size_t v = 0; v < points.size(); ++v) {
    const double len = glm::length(Vec3d(mesh.normals[v]));
    if (!(std::abs(len - 1.0) < 1e-3)) {
      throw ParameterError(fmt::format(
          "compute_transfer: vertex {} has a normal of length {} (a degenerate vertex normal?)", v,
          len));
    }
    points[v].position = Vec3d(mesh.positions[v]);
    points[v].frame = mesh.frame(v);
  }
  return points;
}

TransferResult compute_transfer(const Mesh& mesh, const TransferParams& params) {
  const std::vector<SurfacePoint> points = vertex_points(mesh);
  return compute_transfer(mesh, points, params);
}

TransferResult compute_transfer(const Mesh& occluders, std::span<const SurfacePoint> points,
                                const TransferParams& params) {
  return TransferTracer(occluders, params).compute(points);
}

struct TransferTracer::Tables {
  Tables(const Mesh& occluders, const TransferParams& p)
      : params(p),
        grid(p.local_grid),
        layout(p.cubemap_resolution),
        dirs(p.cubemap_resolution, p.supersampling),
        cells(grid),
        scene(occluders, p.ray_offset_relative) {
    if (p.sh_order > 0) sh_integrator.emplace(dirs, p.sh_order);
  }
  TransferParams params;
  HemisphereGrid grid;
  CubemapLayout layout;
  SupersampledCubemap dirs;
  CellLookup cells;
  EmbreeScene scene;
  std::optional<ShTransferIntegrator> sh_integrator;
  double setup_seconds = 0;
};

TransferTracer::TransferTracer(const Mesh& occluders, const TransferParams& params) {
  const auto t_start = std::chrono::steady_clock::now();
  if (static_cast<long long>(params.local_grid) * params.local_grid > 65535)
    throw ParameterError("compute_transfer: M = S^2 must be below 65536");
  tables_ = std::make_unique<Tables>(occluders, params);
  tables_->setup_seconds = seconds_since(t_start);
}

TransferTracer::~TransferTracer() = default;
TransferTracer::TransferTracer(TransferTracer&&) noexcept = default;
TransferTracer& TransferTracer::operator=(TransferTracer&&) noexcept = default;

TransferResult TransferTracer::compute(std::span<const SurfacePoint> points) const {
  const auto t_start = std::chrono::steady_clock::now();
  const Tables& tb = *tables_;
  const TransferParams& params = tb.params;
  const HemisphereGrid& grid = tb.grid;
  const CubemapLayout& layout = tb.layout;
  const SupersampledCubemap& dirs = tb.dirs;
  const int m = grid.cell_count();
  const int n = layout.pixel_count();
  const CellLookup& cells = tb.cells;
  const EmbreeScene& scene = tb.scene;
  const std::optional<ShTransferIntegrator>& sh_integrator = tb.sh_integrator;
  TransferResult result;
  if (params.sh_order > 0) result.sh.emplace(params.sh_order, points.size());
  for (std::size_t p = 0; p < points.size(); ++p) {
    const double len = glm::length(points[p].frame.n);
    if (!(std::abs(len - 1.0) < 1e-3)) {
      throw ParameterError(fmt::format(
          "compute_transfer: point {} has a normal of length {} (a degenerate vertex normal?)", p,
          len));
    }
  }
  TransferStats& stats = result.stats;
  stats.points = points.size();
  stats.threads = tbb::this_task_arena::max_concurrency();
  stats.subrays = static_cast<std::uint64_t>(points.size()) * dirs.subray_count();
  // The tables' build counts as this call's setup, as when compute_transfer builds them itself.
  stats.seconds_setup = tb.setup_seconds + seconds_since(t_start);

  const auto pixel_dirs = layout.directions();
  tbb::enumerable_thread_specific<ThreadScratch> scratch_tls;
  std::atomic<std::uint64_t> traced{0}, unblocked_total{0}, lifted{0};
  std::atomic<std::int64_t> ns_trace{0}, ns_bin{0}, ns_sh{0};

  TransferAssembler assembler(points.size(), m, n, params.supersampling);
  Progress progress("transfer", static_cast<std::int64_t>(points.size()), params.show_progress);
  std::vector<PointBlock> blocks(std::min(kBatch, points.size()));
  double seconds_points = 0.0, seconds_assemble = 0.0;

  for (std::size_t batch = 0; batch < points.size(); batch += kBatch) {
    const std::size_t batch_end = std::min(points.size(), batch + kBatch);
    const auto t_batch = std::chrono::steady_clock::now();
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(batch, batch_end, 1),
        [&](const tbb::blocked_range<std::size_t>& range) {
          ThreadScratch& s = scratch_tls.local();
          s.vis.resize(static_cast<std::size_t>(n));
          for (std::size_t p = range.begin(); p != range.end(); ++p) {
            const SurfacePoint& point = points[p];
            const std::int64_t t0 = thread_cpu_ns();
            const std::uint64_t rays = scene.visibility(dirs, point.position, point.frame.n, s.vis,
                                                        sh_integrator ? &s.unblocked : nullptr);
            const std::int64_t t1 = thread_cpu_ns();

            // Bin the visible pixels into local cells, then counting-sort by cell: visiting k in
            // increasing order leaves every row sorted by column.
            s.entry_col.clear();
            s.entry_count.clear();
            s.entry_cell.clear();
            std::uint64_t point_unblocked = 0, point_lifted = 0;
            PointBlock& block = blocks[p - batch];
            block.row_nnz.assign(static_cast<std::size_t>(m), 0);
            for (int k = 0; k < n; ++k) {
              const std::uint8_t c = s.vis[k];
              if (c == 0) continue;
              Vec3d l = point.frame.to_local(pixel_dirs[k]);
              if (!(l.z > 0.0)) {
                const double h = std::sqrt(l.x * l.x + l.y * l.y);
                PRT_CHECK(h > 0.0,
                          "point {}: pixel {} straight below the horizon has {} unblocked sub-rays",
                          p, k, c);
                l = Vec3d(l.x / h, l.y / h, kLiftZ);
                ++point_lifted;
              }
              const int j = cells.cell_of(l);
              PRT_CHECK(j >= 0, "point {}: pixel {} has no local cell", p, k);
              s.entry_col.push_back(static_cast<std::uint32_t>(k));
              s.entry_count.push_back(c);
              s.entry_cell.push_back(static_cast<std::uint16_t>(j));
              ++block.row_nnz[j];
              point_unblocked += c;
            }
            const std::size_t nnz = s.entry_col.size();
            s.cursor.resize(static_cast<std::size_t>(m));
            std::uint32_t acc = 0;
            for (int j = 0; j < m; ++j) {
              s.cursor[j] = acc;
              acc += block.row_nnz[j];
            }
            block.cols.resize(nnz);
            block.counts.resize(nnz);
            for (std::size_t e = 0; e < nnz; ++e) {
              const std::uint32_t at = s.cursor[s.entry_cell[e]]++;
              block.cols[at] = s.entry_col[e];
              block.counts[at] = s.entry_count[e];
            }
            const std::int64_t t2 = thread_cpu_ns();

            if (sh_integrator)
              sh_integrator->integrate(point.frame, s.unblocked, result.sh->mutable_matrix(p),
                                       s.sh);
            const std::int64_t t3 = thread_cpu_ns();

            traced.fetch_add(rays, std::memory_order_relaxed);
            unblocked_total.fetch_add(point_unblocked, std::memory_order_relaxed);
            lifted.fetch_add(point_lifted, std::memory_order_relaxed);
            ns_trace.fetch_add(t1 - t0, std::memory_order_relaxed);
            ns_bin.fetch_add(t2 - t1, std::memory_order_relaxed);
            ns_sh.fetch_add(t3 - t2, std::memory_order_relaxed);
            progress.advance(1);
          }
        });
    seconds_points += seconds_since(t_batch);

    const auto t_asm = std::chrono::steady_clock::now();
    if (batch == 0) {
      // Reserve from the first batch's density (T's nnz grows linearly in the points).
      std::size_t first = 0;
      for (std::size_t p = batch; p < batch_end; ++p) first += blocks[p - batch].counts.size();
      assembler.reserve(
          static_cast<std::size_t>(static_cast<double>(first) * static_cast<double>(points.size()) /
                                   static_cast<double>(batch_end) * 1.05));
    }
    for (std::size_t p = batch; p < batch_end; ++p) {
      const PointBlock& block = blocks[p - batch];
      assembler.append(block.row_nnz, block.cols, block.counts);
    }
    seconds_assemble += seconds_since(t_asm);
  }
  progress.finish();

  result.transfer = assembler.finish();
  stats.rays_traced = traced.load();
  stats.rays_unblocked = unblocked_total.load();
  stats.horizon_lifted = lifted.load();
  stats.thread_seconds_trace = ns_trace.load() * 1e-9;
  stats.thread_seconds_bin = ns_bin.load() * 1e-9;
  stats.thread_seconds_sh = ns_sh.load() * 1e-9;
  stats.seconds_points = seconds_points;
  stats.seconds_assemble = seconds_assemble;
  stats.seconds_total = tb.setup_seconds + seconds_since(t_start);
  return result;
}

}  // namespace prt
