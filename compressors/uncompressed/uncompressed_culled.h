#pragma once
// What a frame does not need, for backend `uncompressed` (docs/rendering.md, "Culling"): rows of
// vertices the view does not see, and entries on cube faces the light leaves dark.
//
// A row's columns increase and cube faces are contiguous column ranges (cubemap.h), so the
// entries of face f in row r are one range; FaceTable stores where each face begins in each
// row. relight_culled() is the C++ reference of the kernels uncompressed_rows_faces and
// uncompressed_vertices (uncompressed.cl): it sums every entry into the accumulator the full
// relight (relight_exact, uncompressed_rows) would, in the same order, and leaves out the
// entries of dark faces. Those add count * 0 = 0, and x + 0 = x in float (the accumulators
// start at +0), so the result is bit-identical to the full relight.
#include <cstdint>
#include <span>
#include <vector>

#include "prtlab/base/types.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt::uncompressed {

/// Face starts stored per row: faces 1..5 (face 0 starts at the row's first entry).
inline constexpr int kFaceStarts = 5;

class FaceTable {
 public:
  /// Empty when N is not 6 R^2 or a row has 65,536 entries or more (u16 offsets); callers then
  /// skip no face.
  explicit FaceTable(const TransferMatrix& t);
  bool empty() const { return starts_.empty(); }
  /// kFaceStarts u16 per row: the first entry of faces 1..5, relative to the row's first entry.
  std::span<const std::uint16_t> starts() const { return starts_; }
  std::uint64_t bytes() const { return starts_.size() * sizeof(std::uint16_t); }

 private:
  std::vector<std::uint16_t> starts_;
};

/// out[row] = (T light)[row], bit-identical to relight_exact, for the rows of `vertices` (sorted,
/// unique; every vertex when `all_vertices`), skipping the entries of the faces not in `lit`
/// (bits of lit_faces(); kAllFaces, or an empty `faces`, skips none). Other rows of `out` are not
/// written. TBB over vertices; the result does not depend on the thread count.
void relight_culled(const TransferMatrix& t, const FaceTable& faces, std::span<const Rgb> light,
                    std::uint32_t lit, bool all_vertices, std::span<const std::uint32_t> vertices,
                    std::span<Rgb> out);

}  // namespace prt::uncompressed
