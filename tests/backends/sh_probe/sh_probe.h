#pragma once
// Test-only backend `sh_probe`: relights into the spherical-harmonics basis. Per vertex it
// returns the least-squares SH coefficients (order n, in the local frame) of the exact L*_p:
// c_p = P L*_p with P = pinv(B), B[j, i] = integral of y_i over cell j (radiance_to_bins.h). So
// to_pixel_basis(c) = B P L* is the projection of L* onto the span of the cell integrals of the
// SH basis, and the backend's Frobenius error is known in closed form. It exists to prove that
// evaluation, the conformance suite and the frame loop accept a non-pixel output basis.
#include <memory>
#include <string_view>
#include <vector>

#include "prtlab/compress/compressor.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/stored_model.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt::sh_probe {

inline constexpr std::string_view kName = "sh_probe";
inline constexpr int kStateVersion = 1;

class ShProbeTransfer final : public CompressedTransfer, public StoredModel {
 public:
  ShProbeTransfer(TransferMatrix t, int order);
  static std::unique_ptr<CompressedTransfer> load(const ArchiveReader& archive);

  int order() const { return order_; }
  /// P, order^2 x M row-major (float, as stored).
  const std::vector<float>& projection() const { return p_; }
  const TransferMatrix& matrix() const { return t_; }

  std::string backend() const override { return std::string(kName); }
  StorageReport storage() const override;
  double flops_per_relight() const override;
  double declared_error_bound() const override { return expected_ == 0 ? 0.0 : 1.0; }
  std::optional<double> expected_frobenius_error() const override { return expected_; }
  RadianceBasis output_basis() const override { return RadianceBasis::kSphericalHarmonics; }
  /// B P (T L) in double at the bins.
  ModelRadiance model_radiance(const Cubemap& radiance) const override;
  LightCoeffs project_light(const Cubemap& radiance) const override;
  void relight(const LightCoeffs& light, LocalRadiance& out) const override;
  std::unique_ptr<DeviceRelighter> upload(ClContext& context,
                                          const ParamSet& device_options) const override;
  void save(ArchiveWriter& archive) const override;

 private:
  TransferMatrix t_;
  int order_;
  std::vector<float> p_;
  double expected_ = 0;
};

std::unique_ptr<DeviceRelighter> upload_probe(ClContext& context, const ShProbeTransfer& t);

}  // namespace prt::sh_probe
