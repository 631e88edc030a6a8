#pragma once
// The BRDF-weighted signal of Tsai and Shih 2006 as an input any backend can declare
// (CompressorEntry::inputs.brdf_signal): T folded with one Cook-Torrance BRDF in K separable
// terms (transfer/brdf_weighted_transfer.h), T'_x = Psi T_x, K rows of N pixels per vertex.
//
// A backend that declares it gets, at registration, the parameters of the signal
// (brdf_signal_param_specs(): `signal` = cells | brdf, `brdf_terms`, `brdf_diffuse`,
// `brdf_roughness`, `brdf_fresnel0`), so every backend on the signal reads the same BRDF from the
// same keys, and TransferInput::brdf_signal, which builds the folded rows once per BRDF for
// every backend of a run (brdf_signal_rows()). A backend on the signal relights the K terms and
// then applies the view factor Phi (M x K), so its output is the outgoing radiance towards the
// M view cells, F_K T L, and its declared errors are measured against T' (not T).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "prtlab/compress/params.h"
#include "prtlab/numeric/row_set.h"
#include "prtlab/transfer/brdf_weighted_transfer.h"

namespace prt {

class HemisphereGrid;
class Progress;
class TransferMatrix;
struct TransferInput;

/// The signal a backend compresses: T's M cells, or the K-term BRDF-weighted transfer.
struct BrdfSignalParams {
  bool enabled = false;  ///< `signal = brdf`
  int terms = 16;        ///< K (the paper: 16)
  CookTorrance brdf;
  /// "kd=0.3 m=0.3 F0=0.5 K=16": what the folded rows depend on besides T and the grid.
  std::string key() const;
};

/// The parameters above, appended to the params of every entry that declares the input.
std::span<const ParamSpec> brdf_signal_param_specs();
/// Read from a backend's validated parameters (ParameterError for a bad BRDF).
BrdfSignalParams brdf_signal_params(const ParamSet& params);

/// The folded rows of every vertex as CSR: row x K + k is T'_x's row k, stored at the pixels
/// where T_x has an entry (f32 values, summed in double).
struct FoldedRows {
  BrdfFold fold;
  std::size_t vertices = 0;
  std::size_t pixels = 0;                ///< N
  std::vector<std::uint32_t> offsets;    ///< vertices x K + 1
  std::vector<std::uint16_t> columns16;  ///< when N <= 65536
  std::vector<std::uint32_t> columns32;  ///< otherwise
  std::vector<float> values;
  /// ||T'||_F^2 from the stored (f32) values, in double.
  double squared_norm = 0;

  std::size_t rows() const { return offsets.empty() ? 0 : offsets.size() - 1; }
  /// A view of the rows for the numeric algorithms (valid while this object lives).
  RowSet row_set() const;
  /// Bytes held by the CSR arrays.
  std::uint64_t memory_bytes() const;
};

/// Psi T_x for every vertex. ParameterError naming the problem unless T has the grid's M cells
/// and the fold's K fits M, or when the nonzeros overflow the u32 offsets.
FoldedRows fold_transfer_rows(const TransferMatrix& t, const HemisphereGrid& grid,
                              const BrdfSignalParams& params, Progress& progress);

/// What TransferInput::brdf_signal points to: the folded rows of the most recent BRDF asked for,
/// so that the backends (and sweep points) of one run on the same BRDF fold T once. Safe to call
/// from several threads; the rows live while a caller holds them.
class BrdfSignalSource {
 public:
  std::shared_ptr<const FoldedRows> rows(const TransferMatrix& t, const HemisphereGrid& grid,
                                         const BrdfSignalParams& params, Progress& progress);

 private:
  std::mutex mutex_;
  const TransferMatrix* transfer_ = nullptr;
  std::string key_;
  std::shared_ptr<const FoldedRows> rows_;
};

/// The folded rows of `input`'s T through its source, or built here when the input has none (a
/// TransferInput made by hand, as tests do).
std::shared_ptr<const FoldedRows> brdf_signal_rows(const TransferInput& input,
                                                   const BrdfSignalParams& params,
                                                   Progress& progress);

}  // namespace prt
