#pragma once
// Material `packed`: the sampled BTF stored in fewer bytes for faster shading (README.md). Each
// (texel, view) vector of 3 M values is kept either as IEEE float16 or as 8-bit codes with one
// float scale per vector (code = round(v / s), s = max(v) / 255), the way the central paper
// stores its BTFs in 8 bits. Texels are stored in `tile` x `tile` blocks, views of a texel next
// to each other, so that neighbouring pixels (which hit neighbouring texels at similar views)
// read neighbouring bytes.
//
// Reconstruction: a stored value is half_to_float(h) or s * code; b(u, e, .) is the weighted sum
// of Btf::eval_lights over the 1 or 4 texels x 4 view samples, where an 8-bit vector's scale is
// folded into its weight (w s) * code, in the C++ reference and in packed.cl alike.
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "prtlab/btf/btf.h"
#include "prtlab/compress/material_compressor.h"
#include "prtlab/compress/material_registry.h"

namespace prt::packed {

inline constexpr std::string_view kName = "packed";
inline constexpr int kStateVersion = 1;

enum class Storage { kHalf, kByte };
std::string_view storage_name(Storage s);

class PackedMaterial final : public CompressedMaterial {
 public:
  /// Quantises `btf`. ParameterError when `tile` < 1, a value is negative or not finite, or (for
  /// float16) beyond float16's range.
  PackedMaterial(const Btf& btf, Storage storage, int tile);
  static std::unique_ptr<CompressedMaterial> load(const ArchiveReader& archive);

  std::string backend() const override { return std::string(kName); }
  StorageReport storage() const override;
  double flops_per_pixel() const override;
  double declared_error_bound() const override { return error_bound_; }
  MaterialLightBasis light_basis() const override {
    return MaterialLightBasis::pixel_bins(sampling_.light_side);
  }
  MaterialSampling sampling() const override { return sampling_; }
  Rgb reflectance(int texel, int view, int light) const override;
  void eval_lights(Vec2 uv, Vec3 view_local, std::span<Rgb> out, TexelFilter filter) const override;
  std::unique_ptr<DeviceMaterial> upload(ClContext& context,
                                         std::span<const CompressedMaterial* const> parts,
                                         const ParamSet& device_options) const override;
  void save(ArchiveWriter& archive) const override;

  Storage storage_kind() const { return storage_; }
  int tile() const { return tile_; }
  bool view_independent() const { return stored_views_ == 1 && sampling_.view_count() > 1; }
  int stored_views() const { return stored_views_; }
  /// Storage slot of every texel (the tiled order).
  const std::vector<std::int32_t>& texel_slot() const { return slot_; }
  const std::vector<std::uint16_t>& halves() const { return half_; }
  const std::vector<std::uint8_t>& bytes() const { return byte_; }
  const std::vector<float>& scales() const { return scale_; }
  /// Largest |stored - original| of any value divided by the weight a lookup may give it: the
  /// per-value quantisation step bound (float16: 2^-11 |v| or the subnormal spacing; 8-bit:
  /// s / 2 of the value's vector), for the shading error bound of tests and docs.
  float value_error_bound(int texel, int view, int index) const;
  /// Index of (texel, view)'s stored vector.
  std::size_t vector_index(int texel, int view) const {
    return static_cast<std::size_t>(slot_[static_cast<std::size_t>(texel)]) * stored_views_ +
           (stored_views_ == 1 ? 0 : view);
  }

 private:
  PackedMaterial() = default;
  float decoded(std::size_t vector, int k) const;
  void compute_error_bound(const Btf* original);

  MaterialSampling sampling_;
  nlohmann::json btf_parameters_;
  Storage storage_ = Storage::kByte;
  int tile_ = 4;
  int stored_views_ = 1;
  std::vector<std::int32_t> slot_;
  std::vector<std::uint16_t> half_;
  std::vector<std::uint8_t> byte_;
  std::vector<float> scale_;
  double error_bound_ = 0.0;
};

/// The storage slot of each texel of a U x U tile stored in `tile` x `tile` blocks (row-major
/// blocks, row-major inside each; partial blocks at the right and bottom edges).
std::vector<std::int32_t> tiled_texel_slots(int resolution, int tile);

std::unique_ptr<DeviceMaterial> upload_packed(ClContext& context,
                                              std::span<const PackedMaterial* const> parts);

MaterialEntry registry_entry();

}  // namespace prt::packed
