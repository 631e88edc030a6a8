#pragma once
// Material `svd`: the trivial linear competitors of every BTF factorisation (README.md), stored
// in float32, in one of two modes.
//
//   abrdf      each texel's ABRDF per colour channel, the V x M matrix F(v, j) of the BTF's
//              layout (sample s = view * M + light), truncated to rank K by its SVD:
//              F ~ sum_r U_r(v) W_r(j), W_r = sigma_r V_r (the singular value folded into the
//              light side). K (V + M) floats per texel and channel.
//   texel_pca  every texel's ABRDF (all channels, 3 M V values) a row of the U^2 x 3MV data
//              matrix; a mean row and the K leading principal components shared by all texels,
//              K coefficients per texel: (K + 1) 3 M V + U^2 K floats.
//
// Layouts (the C++ reference and svd.cl read the same arrays):
//   abrdf      view_factors  [((texel V + view) K + r) 3 + channel]
//              light_factors [((texel K + r) M + light) 3 + channel]
//   texel_pca  mean          [view 3M + 3 light + channel]
//              components    [(r V + view) 3M + 3 light + channel]
//              coefficients  [texel K + r]
//
// The declared error bound is the truncation's own residual, from the decomposition, not from
// the shading path: sqrt(discarded / total), with `discarded` the sum of the discarded squared
// singular values (abrdf) or eigenvalues of the centred texel Gram matrix (texel_pca), and
// `total` the BTF's squared Frobenius norm.
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "prtlab/btf/btf.h"
#include "prtlab/compress/material_compressor.h"

namespace prt::svd {

inline constexpr std::string_view kName = "svd";
inline constexpr int kStateVersion = 1;

enum class Mode { kAbrdf, kTexelPca };
std::string_view mode_name(Mode m);
/// ParameterError naming the parameter `mode` unless "abrdf" or "texel_pca".
Mode mode_from(std::string_view name);

struct SvdState {
  Mode mode = Mode::kAbrdf;
  MaterialSampling sampling;
  int rank = 1;                                       ///< K
  std::vector<float> view_factors, light_factors;     ///< abrdf
  std::vector<float> mean, components, coefficients;  ///< texel_pca
  double discarded = 0;  ///< the discarded squared singular values (eigenvalues), summed
  double total = 0;      ///< sum of the BTF's squared values
  nlohmann::json parameters = nlohmann::json::object();  ///< the fit's, for provenance
};

class SvdMaterial final : public CompressedMaterial {
 public:
  /// Checks the arrays' lengths against mode, rank and sampling (ParameterError otherwise).
  explicit SvdMaterial(SvdState state);
  /// Reads what save() wrote; InputError naming the file on anything inconsistent.
  static std::unique_ptr<CompressedMaterial> load(const ArchiveReader& archive);

  std::string backend() const override { return std::string(kName); }
  StorageReport storage() const override;
  double flops_per_pixel() const override;
  double declared_error_bound() const override;
  MaterialLightBasis light_basis() const override {
    return MaterialLightBasis::pixel_bins(state_.sampling.light_side);
  }
  MaterialSampling sampling() const override { return state_.sampling; }
  Rgb reflectance(int texel, int view, int light) const override;
  void eval_lights(Vec2 uv, Vec3 view_local, std::span<Rgb> out, TexelFilter filter) const override;
  std::unique_ptr<DeviceMaterial> upload(ClContext& context,
                                         std::span<const CompressedMaterial* const> parts,
                                         const ParamSet& device_options) const override;
  void save(ArchiveWriter& archive) const override;

  const SvdState& state() const { return state_; }
  Mode mode() const { return state_.mode; }
  int rank() const { return state_.rank; }
  /// Floats per texel of one view factor row (K x RGB) and of one texel's light factors.
  std::size_t view_floats_per_texel() const;
  std::size_t light_floats_per_texel() const;

 private:
  void eval_abrdf(const BtfTexelSamples& ts, const BtfViewSamples& vs, std::span<Rgb> out) const;
  void eval_pca(const BtfTexelSamples& ts, const BtfViewSamples& vs, std::span<Rgb> out) const;
  SvdState state_;
};

/// The device side of `parts` (all svd, one mode and light dimension; ParameterError otherwise).
std::unique_ptr<DeviceMaterial> upload_svd(ClContext& context,
                                           std::span<const SvdMaterial* const> parts);

}  // namespace prt::svd
