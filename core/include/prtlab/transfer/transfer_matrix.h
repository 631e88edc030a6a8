#pragma once
// The exact pixel-basis transfer matrix T (DESIGN.md "Conventions", docs/transfer.md).
//
// For a surface point p with local frame F_p (t, b, n), T_p is an M x N block: M = S^2 local
// cells of the hemisphere grid (hemisphere_grid.h), N = 6 R^2 global cubemap pixels
// (cubemap.h). With c_k in 0..s^2 the supersampled visibility count of pixel k
// (visibility.h), every pixel with c_k > 0 gives exactly one entry
//     T_p[j, k] = c_k / s^2,   j = cell_of(F_p^T d_k),
// d_k the pixel's centre direction. A pixel whose centre is on or below the tangent plane
// but which has unblocked sub-rays (it straddles the horizon) is not dropped: its local
// direction is lifted to z = 1e-9 (renormalised), which puts it in the rim cell at its
// azimuth. So the column sums of T_p are exactly the box-filtered visibility, no energy is
// lost at the horizon, and the horizon error is the unbiased sub-pixel error of
// docs/transfer.md. Each column of a block therefore has at most one non-zero.
//
// Blocks are stacked: row = vertex * M + j. With the light vector L_k = radiance_k *
// solidAngle_k, (T L)[vertex * M + j] is the radiance arriving at the vertex through local
// cell j, integrated over the cell's solid angle (the local radiance L*).
//
// Storage: CSR. Row offsets are u32 (nnz < 2^32 is checked), column indices u16 when
// N <= 65536 and u32 otherwise, values as u8 counts with the common scale 1/s^2, so values
// are exact. Within a row the columns are strictly increasing. Construction is deterministic:
// the same inputs give a bit-identical matrix for any thread count.
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "prtlab/base/types.h"
#include "prtlab/geometry/mesh.h"
#include "prtlab/sphere/local_frame.h"
#include "prtlab/transfer/sh_transfer.h"

namespace prt {

class HemisphereGrid;

/// HemisphereGrid::cell_of for many lookups, with identical results. A table over a cube map
/// of the local frame (256^2 texels per face) holds a texel's cell when the 4 x 4 texel
/// corners of its 3 x 3 neighbourhood all lie in that cell; since that neighbourhood strictly
/// contains the texel and the cell boundaries are smooth at this scale (curvature radius far
/// above a texel), no boundary crosses such a texel. Other texels (cell boundaries, the
/// horizon, face edges: about a tenth) defer to cell_of.
class CellLookup {
 public:
  explicit CellLookup(const HemisphereGrid& grid, int resolution = 256);
  /// Cell of local direction l (z > 0), exactly as grid.cell_of(l).
  int cell_of(const Vec3d& l) const;
  /// Fraction of the upper-hemisphere texels that defer to cell_of.
  double deferred_fraction() const { return deferred_; }

 private:
  const HemisphereGrid* grid_;
  int q_;
  std::vector<std::uint8_t> table_;  ///< 6 faces x q x q; kDefer where undecided
  double deferred_ = 0.0;
};

class TransferMatrix {
 public:
  TransferMatrix() = default;

  /// Assemble from CSR arrays (e.g. when loading). Validates every invariant above (offsets
  /// monotone and ending at nnz, columns < N and strictly increasing per row, counts in
  /// 1..s^2, at most one entry per column of a vertex block) and throws ParameterError naming
  /// the first violation. `columns` are narrowed to u16 when N <= 65536.
  static TransferMatrix from_csr(std::size_t vertices, int local_count, int pixel_count,
                                 int supersampling, std::vector<std::uint32_t> row_offsets,
                                 std::span<const std::uint32_t> columns,
                                 std::vector<std::uint8_t> counts);

  std::size_t vertex_count() const { return vertices_; }
  int local_count() const { return m_; }  ///< M
  std::size_t rows() const { return vertices_ * static_cast<std::size_t>(m_); }
  std::size_t cols() const { return static_cast<std::size_t>(n_); }  ///< N
  std::size_t nnz() const { return counts_.size(); }
  int supersampling() const { return s_; }
  /// Value of a count of 1: 1 / s^2.
  double scale() const { return 1.0 / (static_cast<double>(s_) * s_); }

  /// Size rows() + 1; row i spans [row_offsets[i], row_offsets[i+1]).
  std::span<const std::uint32_t> row_offsets() const { return row_offsets_; }
  /// True when column indices are stored as u16 (N <= 65536): columns16() is the index array,
  /// else columns32().
  bool narrow_columns() const { return narrow_; }
  std::span<const std::uint16_t> columns16() const { return cols16_; }
  std::span<const std::uint32_t> columns32() const { return cols32_; }
  std::uint32_t column(std::size_t i) const { return narrow_ ? cols16_[i] : cols32_[i]; }
  /// Exact values as counts of unblocked sub-rays (1..s^2).
  std::span<const std::uint8_t> counts() const { return counts_; }
  float value(std::size_t i) const { return static_cast<float>(counts_[i] * scale()); }
  /// Entry (row, col), 0 where not stored (binary search in the row).
  double at(std::size_t row, std::uint32_t col) const;

  /// Bytes of the CSR arrays (offsets + column indices + counts).
  std::uint64_t memory_bytes() const;
  /// The paper's "data size": the dense matrix at one byte per entry (vertices x M x N).
  std::uint64_t dense_bytes() const { return static_cast<std::uint64_t>(rows()) * cols(); }

  /// Bit-exact comparison of shape, scale and arrays.
  friend bool operator==(const TransferMatrix&, const TransferMatrix&) = default;

 private:
  friend class TransferAssembler;
  std::size_t vertices_ = 0;
  int m_ = 0;
  int n_ = 0;
  int s_ = 1;
  bool narrow_ = true;
  std::vector<std::uint32_t> row_offsets_{0};
  std::vector<std::uint16_t> cols16_;
  std::vector<std::uint32_t> cols32_;
  std::vector<std::uint8_t> counts_;
};

struct TransferParams {
  int cubemap_resolution = 32;        ///< R: N = 6 R^2
  int local_grid = 8;                 ///< S: M = S^2
  int supersampling = 2;              ///< s: s x s visibility rays per pixel
  double ray_offset_relative = 1e-4;  ///< origin offset along the normal / bbox diagonal
  int sh_order = 0;                   ///< 0: no SH transfer; 1..10 (5 gives 25 x 25 per vertex)
  bool show_progress = true;  ///< a terminal progress bar (also off under Progress::set_quiet)
};

/// A receiver point: where visibility is computed, and the frame that defines its local cells.
struct SurfacePoint {
  Vec3d position{0.0};
  LocalFrame frame;
};

/// Counters and timings of one transfer computation.
struct TransferStats {
  std::size_t points = 0;
  int threads = 0;                   ///< TBB worker concurrency used (summed over ranks)
  int ranks = 1;                     ///< processes the points were spread over
  std::uint64_t subrays = 0;         ///< points * N * s^2 sub-directions considered
  std::uint64_t rays_traced = 0;     ///< sub-rays strictly above the tangent plane (cast)
  std::uint64_t rays_unblocked = 0;  ///< of those, the ones that escaped
  std::uint64_t horizon_lifted = 0;  ///< entries whose pixel centre was on/below the tangent plane
  double seconds_total = 0;          ///< wall clock of compute_transfer
  double seconds_setup = 0;          ///< BVH build and direction / SH tables (wall)
  double seconds_points = 0;         ///< the parallel per-point pass (wall)
  double seconds_assemble = 0;       ///< serial appends of the per-point blocks (wall)
  // CPU seconds summed over threads (CLOCK_THREAD_CPUTIME_ID, so not inflated by a loaded machine):
  double thread_seconds_trace = 0;  ///< Embree occlusion packets
  double thread_seconds_bin = 0;    ///< pixel -> local cell, block sort
  double thread_seconds_sh = 0;     ///< SH transfer quadrature
  /// Traced rays per second of the per-point pass (wall clock, all threads).
  double rays_per_second() const { return seconds_points > 0 ? rays_traced / seconds_points : 0.0; }
  /// Traced rays per CPU second of tracing (one thread's throughput).
  double rays_per_trace_cpu_second() const {
    return thread_seconds_trace > 0 ? rays_traced / thread_seconds_trace : 0.0;
  }
};

struct TransferResult {
  TransferMatrix transfer;
  std::optional<ShTransfer> sh;  ///< when params.sh_order > 0
  TransferStats stats;
};

/// What compute_transfer builds before its per-point pass (the occluders' BVH, the direction,
/// cell and SH tables), kept for any number of point sets: compute(points) equals
/// compute_transfer(occluders, points, params) bit for bit, so a run that splits the points
/// (compute_transfer_distributed) builds the tables once per process.
class TransferTracer {
 public:
  TransferTracer(const Mesh& occluders, const TransferParams& params);
  ~TransferTracer();
  TransferTracer(TransferTracer&&) noexcept;
  TransferTracer& operator=(TransferTracer&&) noexcept;
  /// T (and the SH transfer) of these points; the stats' setup time includes the tables' build.
  TransferResult compute(std::span<const SurfacePoint> points) const;

 private:
  struct Tables;
  std::unique_ptr<Tables> tables_;
};

/// The receiver points of every vertex of `mesh` (its positions and frames); ParameterError on
/// a missing or degenerate normal.
std::vector<SurfacePoint> vertex_points(const Mesh& mesh);

/// T (and the SH transfer when asked) for every vertex of `mesh`, which is also the occluder.
/// Requires normals (tangents where present define the frames: Mesh::frame).
TransferResult compute_transfer(const Mesh& mesh, const TransferParams& params);
/// T for arbitrary receiver points against the occluder mesh (tests, partial scenes).
TransferResult compute_transfer(const Mesh& occluders, std::span<const SurfacePoint> points,
                                const TransferParams& params);

}  // namespace prt
