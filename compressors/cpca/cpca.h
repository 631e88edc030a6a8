#pragma once
// Backend `cpca`: clustered principal component analysis of the rows of T (Sloan et al. 2003,
// sections 4 and 6; compressors/cpca/README.md). Every row of T (one local cell of one vertex, a
// 6,144-dimensional light response) is approximated in the affine subspace of its cluster:
//
//   T~[row] = rep_0(c) + sum_i w_i rep_i(c),     c = cluster of the row, i < k_c,
//
// so a relight costs one dot product with L per representative (per cluster: mean and k_c
// vectors) and then, per row, a weighted sum of its cluster's k_c + 1 scalars (the paper's
// per-cluster CPU products and per-vertex GPU blend, with the cell rows as the signals).
//
// With `signal=brdf` (core compress/brdf_signal.h) the rows are those of the BRDF-weighted
// transfer instead, K folded rows Psi T_x per vertex, and the relight ends with the view factor
// Phi (M x K, f32, stored): L*_x = Phi (T~'_x L), the outgoing radiance towards the M view cells.
//
// Storage: per row the cluster id (u8 / u16 / u32 by cluster count) and its k_c weights (f32,
// IEEE half, or s8 codes times a per-row f32 scale); per cluster its mean and vectors as f32
// N-vectors, and for the adaptive method the count k_c (u16 per cluster). Row weight offsets
// follow from the ids and counts and are not stored.
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "prtlab/compress/compressor.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/stored_model.h"
#include "prtlab/numeric/clustered_pca.h"

namespace prt::cpca {

inline constexpr std::string_view kName = "cpca";
/// Version of this backend's archive sections and metadata (bumped when they change).
inline constexpr int kStateVersion = 2;

enum class WeightFormat { kFloat32, kFloat16, kS8 };
std::string_view to_string(WeightFormat f);
WeightFormat weight_format_from(std::string_view name);
std::string_view to_string(CpcaMethod m);

/// The arrays both relight paths read.
struct CpcaArrays {
  std::size_t vertices = 0;
  int local_count = 0;  ///< M: the values per vertex of the relight
  int pixel_count = 0;  ///< N
  /// K of the BRDF-weighted signal, whose K rows per vertex are blended and then multiplied by
  /// `view`; 0: the rows are T's M cells.
  int view_terms = 0;
  std::vector<float> view;  ///< Phi, M x K row after row (signal=brdf)
  CpcaMethod method = CpcaMethod::kIterative;
  WeightFormat format = WeightFormat::kFloat32;
  /// Representatives, rep after rep (N floats each): cluster c owns reps first[c] (its mean)
  /// to first[c + 1] - 1 (its vectors).
  std::vector<float> reps;
  std::vector<std::uint32_t> first{0};  ///< clusters + 1
  std::vector<std::uint32_t> ids;       ///< rows: the cluster of each row
  /// rows + 1: row r's weights are weight_values[weight_offsets[r] ..]; derived, not stored.
  std::vector<std::uint32_t> weight_offsets{0};
  std::vector<float> weights32;          ///< format float32
  std::vector<std::uint16_t> weights16;  ///< format float16: IEEE half bits
  std::vector<std::int8_t> codes;        ///< format s8
  std::vector<float> row_scales;         ///< format s8: the value of code 1, per row
  /// The weights as the relight multiplies them (decoded halves; s8 codes as floats, the row
  /// scale applied after the sum): a cache of the stored weights, not stored itself.
  std::vector<float> weight_values;
  /// ||T~ - T||_F / ||T||_F of the stored model, computed in double while compressing.
  double frobenius_error = 0;

  std::size_t rows() const { return ids.size(); }
  /// Stored rows per vertex: K for the BRDF signal, else M.
  int rows_per_vertex() const { return view_terms > 0 ? view_terms : local_count; }
  std::size_t clusters() const { return first.size() - 1; }
  std::size_t rep_count() const { return first.back(); }
  int vectors_of(std::size_t c) const { return static_cast<int>(first[c + 1] - first[c] - 1); }
  /// Bytes per stored cluster id: 1, 2 or 4.
  std::size_t id_bytes() const;
  /// Every cluster has the same number of vectors (static and iterative), or -1.
  int uniform_vectors() const;
};

/// Fills weight_offsets and weight_values from ids, first and the stored weights.
void derive_row_layout(CpcaArrays& a);

/// The light's dot product with every representative (rep_count() RGB values), summed in the
/// kernel's order: 64 strided partial sums per rep, then a pairwise tree.
std::vector<Rgb> representative_dots(const CpcaArrays& a, std::span<const Rgb> light);
/// out[row] = q[first] + sum_i w_i q[first + 1 + i] for every row (s8: q[first] + scale *
/// sum_i code_i q[...]), TBB over rows, in the kernel's order.
void blend_rows(const CpcaArrays& a, std::span<const Rgb> q, std::span<Rgb> out);
/// out[x M + o] = sum_k Phi[o, k] terms[x K + k] (signal=brdf), k ascending, as the kernel sums.
void apply_view(const CpcaArrays& a, std::span<const Rgb> terms, std::span<Rgb> out);
/// The same for the rows of the listed vertices only.
void blend_vertex_rows(const CpcaArrays& a, std::span<const Rgb> q,
                       std::span<const std::uint32_t> vertices, std::span<Rgb> out);

class CpcaTransfer final : public CompressedTransfer, public StoredModel {
 public:
  explicit CpcaTransfer(CpcaArrays arrays) : a_(std::move(arrays)) {}
  static std::unique_ptr<CompressedTransfer> load(const ArchiveReader& archive);

  const CpcaArrays& arrays() const { return a_; }

  std::string backend() const override { return std::string(kName); }
  StorageReport storage() const override;
  /// Per channel: 2N per representative (its dot with L) plus 2 k_c per row (its blend; s8
  /// adds the scale's multiply).
  double flops_per_relight() const override;
  /// Lossy without a guaranteed bound: CPCA minimises the squared error of T, not of T L. For
  /// the BRDF signal the Frobenius error is against T' = Psi T (equal, relatively, to the error
  /// of Phi T' over the view cells, whose weight makes Phi orthonormal).
  double declared_error_bound() const override { return kNoErrorBound; }
  std::optional<double> expected_frobenius_error() const override { return a_.frobenius_error; }
  /// Every row rebuilt as its N-vector rep_0 + s sum_i w_i rep_i (double) and dotted with L.
  ModelRadiance model_radiance(const Cubemap& radiance) const override;
  LightCoeffs project_light(const Cubemap& radiance) const override;
  void relight(const LightCoeffs& light, LocalRadiance& out) const override;
  /// Not for the BRDF signal, whose vertices mix K rows through Phi (relight_vertices() then
  /// relights every vertex).
  bool supports_vertex_subset() const override { return a_.view_terms == 0; }
  void relight_vertices(const LightCoeffs& light, std::span<const std::uint32_t> vertices,
                        LocalRadiance& out) const override;
  std::unique_ptr<DeviceRelighter> upload(ClContext& context,
                                          const ParamSet& device_options) const override;
  void save(ArchiveWriter& archive) const override;

 private:
  CpcaArrays a_;
};

/// The arrays resident on `context`'s device. The context must outlive the relighter.
std::unique_ptr<DeviceRelighter> upload_cpca(ClContext& context, const CpcaArrays& arrays);

/// The model of clustered_pca() (points = T's rows) as stored: f32 representatives and weights
/// in `format`, with the stored model's Frobenius error against `t`.
CpcaArrays encode(const ClusteredPca& model, const RowSet& rows, std::size_t vertices,
                  int local_count, int pixel_count, CpcaMethod method, WeightFormat format);

CompressorEntry registry_entry();

}  // namespace prt::cpca
