#pragma once
// Saving and loading the transfer stage (T and the optional SH transfer) as a prtlab archive
// (docs/file-format.md), kind "transfer-matrix".
//
// Sections: "row_offsets" u32 (rows + 1), "columns" u16 or u32 (nnz), "counts" u8 (nnz),
// and when present "sh" f64 (vertices * n * n, row-major per vertex).
// Metadata: vertices, local_count (M), pixel_count (N), supersampling (s), sh_order, and the
// stats of the computation that produced it (so a cache hit can report them).
#include "prtlab/storage/archive.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt {

inline constexpr std::string_view kTransferArchiveKind = "transfer-matrix";
inline constexpr std::uint32_t kTransferArchiveVersion = 1;

ArchiveWriter save_transfer(const TransferResult& result);
/// Verifies every CSR invariant (TransferMatrix::from_csr); a violation is an InputError naming the
/// file.
TransferResult load_transfer(const ArchiveReader& archive);

}  // namespace prt
