#pragma once
// Material `full`: the sampled BTF itself, float32 RGB per (texel, view, light bin), as
// generated (docs/btf.md). The lossless reference every other material is measured against,
// and the speed baseline for shading (compressors/full/README.md).
//
// Parameters: only the shared "seed", which nothing here uses. No device options.
#include <memory>
#include <string>
#include <string_view>

#include "prtlab/btf/btf.h"
#include "prtlab/compress/material_compressor.h"
#include "prtlab/compress/material_registry.h"

namespace prt::full {

inline constexpr std::string_view kName = "full";
/// Version of this material's archive sections and metadata (bumped when they change).
inline constexpr int kStateVersion = 1;

class FullMaterial final : public CompressedMaterial {
 public:
  /// Shares `btf` (no copy). ParameterError when it is null.
  explicit FullMaterial(std::shared_ptr<const Btf> btf);
  /// The state written by save() (InputError naming the file when it is inconsistent).
  static std::unique_ptr<CompressedMaterial> load(const ArchiveReader& archive);

  const Btf& btf() const { return *btf_; }

  std::string backend() const override { return std::string(kName); }
  StorageReport storage() const override;
  double flops_per_pixel() const override;
  double declared_error_bound() const override { return 0.0; }
  MaterialLightBasis light_basis() const override {
    return MaterialLightBasis::pixel_bins(btf_->light_side());
  }
  MaterialSampling sampling() const override { return sampling_of(*btf_); }
  Rgb reflectance(int texel, int view, int light) const override;
  void eval_lights(Vec2 uv, Vec3 view_local, std::span<Rgb> out, TexelFilter filter) const override;
  /// Btf::shade: the sum the shading of the raw BTF has always computed, bit for bit.
  Rgb shade(Vec2 uv, Vec3 view_local, std::span<const Rgb> light,
            TexelFilter filter) const override;
  std::unique_ptr<DeviceMaterial> upload(ClContext& context,
                                         std::span<const CompressedMaterial* const> parts,
                                         const ParamSet& device_options) const override;
  void save(ArchiveWriter& archive) const override;

 private:
  std::shared_ptr<const Btf> btf_;
};

/// Every part's BTF in one device buffer (each distinct BTF once; a view-independent one with its
/// view 0 only, U^2 x M x 3 floats) with per-part offsets and (U, view_side, view_independent)
/// tables, evaluated by kernels/btf_table_material.cl (render/btf_table_material.h). The context
/// must outlive the result.
std::unique_ptr<DeviceMaterial> upload_full(ClContext& context,
                                            std::span<const FullMaterial* const> parts);

/// The registry entry (registered by full.cpp).
MaterialEntry registry_entry();

}  // namespace prt::full
