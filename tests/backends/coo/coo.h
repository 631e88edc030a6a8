#pragma once
// Test-only backend `coo`: T as coordinate triplets (u32 row, u32 column, f32 value per entry,
// sorted by row). It exists to prove that a backend is its folder alone: this folder holds its
// code, kernel, test, doc page and deps.cmake, and no file outside it names it. With
// keep < 1 it is lossy (each row keeps its largest entries), the case of a backend that has no
// proven bound but declares the Frobenius error it expects.
#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

#include "prtlab/compress/compressor.h"
#include "prtlab/compress/compressor_registry.h"

namespace prt::coo {

inline constexpr std::string_view kName = "coo";
inline constexpr int kStateVersion = 1;

/// True when deps.cmake was applied to this backend's objects (and only to them).
bool built_with_its_deps();

struct Triplets {
  double expected_frobenius = 0;  ///< ||T~ - T||_F / ||T||_F of the dropped entries
  std::size_t vertices = 0;
  int local_count = 0;  ///< M
  int pixel_count = 0;  ///< N
  std::vector<std::uint32_t> rows, columns;
  std::vector<float> values;
};

class CooTransfer final : public CompressedTransfer {
 public:
  explicit CooTransfer(Triplets t) : t_(std::move(t)) {}
  static std::unique_ptr<CompressedTransfer> load(const ArchiveReader& archive);

  const Triplets& triplets() const { return t_; }
  std::string backend() const override { return std::string(kName); }
  StorageReport storage() const override;
  double flops_per_relight() const override { return 2.0 * static_cast<double>(t_.values.size()); }
  /// Lossless when nothing was dropped; otherwise no bound is proven (a dropped entry may carry
  /// a whole row's light), only the expected Frobenius error is declared.
  double declared_error_bound() const override { return t_.expected_frobenius == 0 ? 0.0 : 1.0; }
  std::optional<double> expected_frobenius_error() const override { return t_.expected_frobenius; }
  /// entries_kept: the triplets stored (a backend metric the harness tests read back).
  std::vector<BackendMetric> backend_metrics() const override {
    return {{"entries_kept", static_cast<double>(t_.values.size()), "triplets of T kept"}};
  }
  LightCoeffs project_light(const Cubemap& radiance) const override;
  void relight(const LightCoeffs& light, LocalRadiance& out) const override;
  std::unique_ptr<DeviceRelighter> upload(ClContext& context,
                                          const ParamSet& device_options) const override;
  void save(ArchiveWriter& archive) const override;

 private:
  void check_light(const LightCoeffs& light) const;
  Triplets t_;
};

std::unique_ptr<DeviceRelighter> upload_triplets(ClContext& context, const Triplets& t);

}  // namespace prt::coo
