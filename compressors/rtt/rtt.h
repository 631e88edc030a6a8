#pragma once
// Material `rtt`: the radiance transfer texture of SH bi-scale radiance transfer (Sloan, Liu,
// Shum, Snyder 2004, section 5; compressors/rtt/README.md). Per texel and view sample the BTF's
// light side projected onto the SH basis over the local light direction:
//
//   rtt(u, e)_i = sum_j b(u, e, d_j) B[j, i],   B[j, i] = integral over light cell j of y_i
//
// (the paper's eq. 5 weights y_i(l_k) times the solid angle of light sample k, with the cell
// integral of y_i in place of its centre value times the cell's solid angle; sh_cell_integrals in
// transfer/radiance_to_bins.h). With it, shading SH local radiance e (coefficients in the local
// frame) is one dot product per channel, B(x, e) = sum_i rtt(u, e)_i e_i, and equals exactly the
// full BTF's shading of the radiance evaluated at the bins (to_pixel_basis): both are
// sum_j b_j integral over cell j of sum_i e_i y_i. The light basis is SH(order); a view-
// independent BTF gives a view-independent texture, which skips the view interpolation.
//
// Parameters: `order` (1..10; the paper: 5, n = 25 coefficients).
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "prtlab/btf/btf.h"
#include "prtlab/compress/material_compressor.h"
#include "prtlab/compress/material_registry.h"

namespace prt::rtt {

inline constexpr std::string_view kName = "rtt";
/// Version of this material's archive sections and metadata (bumped when they change).
inline constexpr int kStateVersion = 1;
inline constexpr int kMaxOrder = 10;

/// The SH projection of `btf`'s light side: a table with the BTF's texels and views whose
/// "light" axis holds the order^2 coefficients (light_side() = order), summed in double.
Btf project_btf(const Btf& btf, int order);

class RttMaterial final : public CompressedMaterial {
 public:
  /// `table` from project_btf of a BTF sampled as `sampling`; `error` the relative L2 error of
  /// reflectance() against that BTF (computed by the compressor, stored).
  RttMaterial(MaterialSampling sampling, std::shared_ptr<const Btf> table, double error);
  static std::unique_ptr<CompressedMaterial> load(const ArchiveReader& archive);

  int order() const { return table_->light_side(); }
  const Btf& table() const { return *table_; }

  std::string backend() const override { return std::string(kName); }
  StorageReport storage() const override;
  /// 2 n per view sample read (1 or 4) to interpolate, and 2 n for the dot product.
  double flops_per_pixel() const override;
  /// The measured relative L2 error of reflectance() against the BTF it came from: the SH
  /// truncation of the light side (no a-priori bound exists for a general BTF).
  double declared_error_bound() const override { return error_; }
  MaterialLightBasis light_basis() const override {
    return MaterialLightBasis::spherical_harmonics(order());
  }
  MaterialSampling sampling() const override { return sampling_; }
  /// The texture's SH reconstruction averaged over light cell j: (1 / Omega_j) sum_i rtt_i
  /// B[j, i], in the full BTF's units.
  Rgb reflectance(int texel, int view, int light) const override;
  void eval_lights(Vec2 uv, Vec3 view_local, std::span<Rgb> out, TexelFilter filter) const override;
  Rgb shade(Vec2 uv, Vec3 view_local, std::span<const Rgb> light,
            TexelFilter filter) const override;
  std::unique_ptr<DeviceMaterial> upload(ClContext& context,
                                         std::span<const CompressedMaterial* const> parts,
                                         const ParamSet& device_options) const override;
  void save(ArchiveWriter& archive) const override;

 private:
  MaterialSampling sampling_;
  std::shared_ptr<const Btf> table_;
  double error_ = 0;
  std::vector<double> cells_;  ///< B (M x n, row-major) divided by the cell solid angle
};

/// The registry entry (registered by rtt.cpp).
MaterialEntry registry_entry();

}  // namespace prt::rtt
