#pragma once
// Backend `bicluster`: the lossless biclustering of T of Sun et al. (bicluster_search.h), relit
// in two phases per Algorithm 2: phase 1 one RGB scalar P_i = sum_m t_m L[k_m] per bicluster,
// phase 2 per row the sum of P_i over the biclusters touching it plus the row's residual 1x1
// terms, times 1/s^2. docs/backends/bicluster.md gives the byte layout and measurements.
//
// Parameters: only the shared "seed" (the random seeds of the search).
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "bicluster/bicluster_search.h"
#include "prtlab/compressor.h"
#include "prtlab/compressor_registry.h"

namespace prt {

class TransferMatrix;

namespace bicluster {

inline constexpr std::string_view kName = "bicluster";
/// Version of this backend's archive sections and metadata (bumped when they change).
inline constexpr int kStateVersion = 1;

/// The stored form (the arrays of docs/backends/bicluster.md).
struct BiclusterArrays {
  std::size_t vertices = 0;
  int local_count = 0;  ///< M
  int pixel_count = 0;  ///< N
  int supersampling = 1;
  std::vector<std::uint32_t> bic_col_offsets{0};  ///< per bicluster + 1
  std::vector<std::uint32_t> bic_columns;         ///< global pixel k per bicluster column
  std::vector<std::int16_t> bic_constants;        ///< t_m as signed counts
  std::vector<std::uint32_t> row_bic_offsets;     ///< per row + 1 (I_j of Algorithm 2)
  std::vector<std::uint32_t> row_bics;            ///< bicluster ids per row, increasing
  std::vector<std::uint32_t> res_offsets;         ///< per row + 1
  std::vector<std::uint32_t> res_columns;         ///< residual 1x1 terms, increasing per row
  std::vector<std::int16_t> res_counts;           ///< signed counts
  std::size_t rows() const { return vertices * static_cast<std::size_t>(local_count); }
  std::size_t bicluster_count() const { return bic_col_offsets.size() - 1; }
  double scale() const { return 1.0 / (static_cast<double>(supersampling) * supersampling); }
};

/// T's counts as the search's signed CSR.
SparseCounts counts_of(const TransferMatrix& t);
/// Pack a search result (duplicate residual terms summed, zeros dropped).
BiclusterArrays pack(const Biclustering& b, const TransferMatrix& t);
/// The counts the arrays stand for (sum of biclusters and residual terms).
SparseCounts reconstruct(const BiclusterArrays& a);

class BiclusterTransfer final : public CompressedTransfer {
 public:
  explicit BiclusterTransfer(BiclusterArrays arrays);
  static std::unique_ptr<CompressedTransfer> load(const ArchiveReader& archive);

  const BiclusterArrays& arrays() const { return a_; }
  std::string backend() const override { return std::string(kName); }
  StorageReport storage() const override;
  /// sum W(B_i) + 2 per residual term.
  double flops_per_relight() const override;
  double declared_error_bound() const override { return 0.0; }
  LightCoeffs project_light(const Cubemap& radiance) const override;
  void relight(const LightCoeffs& light, LocalRadiance& out) const override;
  std::unique_ptr<DeviceRelighter> upload(ClContext& context) const override;
  void save(ArchiveWriter& archive) const override;

 private:
  bool narrow() const { return a_.pixel_count <= 65536; }
  BiclusterArrays a_;
};

std::unique_ptr<DeviceRelighter> upload_arrays(ClContext& context, const BiclusterArrays& a);

CompressorEntry registry_entry();

}  // namespace bicluster
}  // namespace prt
