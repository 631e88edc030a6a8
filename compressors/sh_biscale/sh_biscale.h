#pragma once
// Backend `sh_biscale`: the macro scale of SH bi-scale radiance transfer (Sloan, Liu, Shum,
// Snyder 2004; compressors/sh_biscale/README.md). Per vertex p the n x n matrix M_p (n =
// order^2) of the transfer stage (sh_transfer.h) maps the global SH light l to the local SH
// coefficients of the incident radiance, rotation into the vertex frame and shadowing included:
//
//   zero projection           e_p = M_p l                     (the paper: radiance below the
//                                                              horizon is zero)
//   least-squares projection  e_p = A^-1 M_p l                (hemisphere_projection.h: the
//                                                              coefficients that fit the radiance
//                                                              best over the upper hemisphere)
//
// stored as f32 n x n per vertex. The relight is one matrix-vector product per vertex (output
// basis kSphericalHarmonics); the radiance transfer texture material (`rtt`) shades it directly,
// a pixel-bin material through to_pixel_basis. The size knob is the order.
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "prtlab/compress/compressor.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/stored_model.h"

namespace prt::sh_biscale {

inline constexpr std::string_view kName = "sh_biscale";
/// Version of this backend's archive sections and metadata (bumped when they change).
inline constexpr int kStateVersion = 2;
/// The SH order of the transfer the entry asks prepare_scene() for (BackendInputs are static):
/// the `order` parameter takes the leading order^2 x order^2 block, which is exactly the
/// transfer of that order (SH index sets of lower orders are prefixes).
inline constexpr int kInputOrder = 10;

enum class Projection { kZero, kLeastSquares };
std::string_view to_string(Projection p);

/// The arrays both relight paths read.
struct ShBiscaleArrays {
  std::size_t vertices = 0;
  int order = 0;
  Projection projection = Projection::kZero;
  /// vertices x n x n, vertex after vertex, each row-major: matrices[(p n + i) n + k], i the
  /// local and k the global coefficient.
  std::vector<float> matrices;
  /// M: the local bins the output is evaluated at (to_pixel_basis), for the stored model.
  int local_count = 0;
  /// ||T~ - T||_F / ||T||_F of the stored matrices read as the pixel-basis transfer
  /// T~_p = B M_p Y (sh_matrix_model.h), computed in double while compressing.
  double frobenius_error = 0;
  int n() const { return order * order; }
};

/// The f32 matrices of every vertex from the SH transfer (the leading n x n block of each M_p),
/// multiplied by A^-1 from the left for the least-squares projection (in double, then rounded).
std::vector<float> vertex_matrices(const ShTransfer& sh, int order, Projection projection);

/// out[p n + i] = sum_k M_p[i, k] l_k for the listed vertices (all when `vertices` is empty and
/// `all` is set), summed over k in increasing order in float, as the kernel does.
void relight_rows(const ShBiscaleArrays& a, std::span<const Rgb> light,
                  std::span<const std::uint32_t> vertices, bool all, std::span<Rgb> out);

class ShBiscaleTransfer final : public CompressedTransfer, public StoredModel {
 public:
  explicit ShBiscaleTransfer(ShBiscaleArrays arrays) : a_(std::move(arrays)) {}
  static std::unique_ptr<CompressedTransfer> load(const ArchiveReader& archive);

  const ShBiscaleArrays& arrays() const { return a_; }
  /// "sh<order>": the basis of project_light().
  std::string light_basis() const;

  std::string backend() const override { return std::string(kName); }
  StorageReport storage() const override;
  /// 2 n^2 per vertex (the paper's count: one n x n matrix-vector product).
  double flops_per_relight() const override;
  /// No guarantee for T L: the SH truncation of the light and of the transferred radiance is
  /// not bounded.
  double declared_error_bound() const override { return kNoErrorBound; }
  /// Of the stored f32 matrices against T, at the bins: the SH truncation of light and output.
  std::optional<double> expected_frobenius_error() const override { return a_.frobenius_error; }
  /// B M_p (Y L) in double per vertex (sh_matrix_model.h).
  ModelRadiance model_radiance(const Cubemap& radiance) const override;
  RadianceBasis output_basis() const override { return RadianceBasis::kSphericalHarmonics; }
  LightCoeffs project_light(const Cubemap& radiance) const override;
  void relight(const LightCoeffs& light, LocalRadiance& out) const override;
  bool supports_vertex_subset() const override { return true; }
  void relight_vertices(const LightCoeffs& light, std::span<const std::uint32_t> vertices,
                        LocalRadiance& out) const override;
  std::unique_ptr<DeviceRelighter> upload(ClContext& context,
                                          const ParamSet& device_options) const override;
  void save(ArchiveWriter& archive) const override;

 private:
  void check_light(const LightCoeffs& light) const;

  ShBiscaleArrays a_;
};

/// The arrays resident on `context`'s device. The context must outlive the relighter.
std::unique_ptr<DeviceRelighter> upload_sh_biscale(ClContext& context, const ShBiscaleArrays& a,
                                                   const std::string& light_basis);

CompressorEntry registry_entry();

}  // namespace prt::sh_biscale
