#pragma once
// BTF generation by ray tracing a periodic meso-structure with Embree (docs/btf.md).
//
// For every texel, 2 x 2 (supersampling^2) points q on the reference plane z = 0 inside the
// texel, every view direction e and every light direction l (the cell centres of the view and
// light hemisphere grids):
//   masking    the visible point p is the first hit of the ray from above along -e through q
//              (origin q + e * (max_height + margin) / e.z);
//   shadowing  p is lit when the ray from p (offset along the geometric normal) towards l
//              leaves the tile's slab z <= max_height without a hit;
//   value      f_r(p; l, e) * max(0, n_p . l) when lit, else 0, averaged over the q of the
//              texel; with interreflection, one bounce of indirect light is added: a
//              cosine-weighted, stratified set of rays from p picks up the direct light that
//              the first surface they hit reflects towards p.
// Rays that leave the tile through a side re-enter through the opposite side (the tile is
// periodic), so meso-structure of any height and any grazing angle is handled exactly.
// Deterministic: the same inputs give bitwise the same BTF (any thread count).
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string_view>

#include "prtlab/btf/btf.h"
#include "prtlab/btf/btf_materials.h"
#include "prtlab/storage/content_hash.h"
#include "prtlab/storage/stage_cache.h"

namespace prt {

/// Version of the generator's algorithm; part of the cache key.
inline constexpr std::uint32_t kBtfGeneratorVersion = 2;  // 2: cell-mean cosine per light

struct BtfParams {
  int resolution = 32;              ///< U texels per side (1..1024)
  int view_side = 12;               ///< V = view_side^2 view directions (1..64)
  int light_side = 8;               ///< M = light_side^2 light directions (1..64)
  int supersampling = 2;            ///< points per texel side (1..8)
  int interreflection_samples = 0;  ///< 0: off; else one bounce with this many rays (1..1024)
  int geometry_grid = 0;            ///< height-field cells per side; 0: max(128, 4 U)
  std::uint32_t seed = 1;           ///< for the interreflection ray pattern

  /// Throws ParameterError naming the offending parameter.
  void validate() const;
  int effective_geometry_grid() const;
  nlohmann::json to_json() const;
};

/// Embree scene of a meso-structure with wrap-around ray queries (thread-safe for queries).
class MesoTracer {
 public:
  explicit MesoTracer(const MesoStructure& meso);
  ~MesoTracer();
  MesoTracer(MesoTracer&&) noexcept;
  MesoTracer& operator=(MesoTracer&&) noexcept;
  MesoTracer(const MesoTracer&) = delete;
  MesoTracer& operator=(const MesoTracer&) = delete;

  struct Hit {
    bool found = false;
    Vec3 position{0.f};          ///< x, y wrapped into [0, 1)
    Vec3 geometric_normal{0.f};  ///< unit, facing the ray's origin
    Vec3 shading_normal{0.f};    ///< unit, same side as geometric_normal
    int brdf = 0;
    std::uint32_t triangle = 0;
  };
  /// First hit of the ray (origin anywhere in or above the tile, dir need not be unit).
  Hit trace(Vec3 origin, Vec3 dir) const;
  /// The surface point visible from direction e (unit, e.z > 0) through (x, y) on z = 0.
  Hit visible_point(Vec2 xy, Vec3 e) const;
  /// True when the ray towards dir hits the meso-structure before it rises above max_height.
  bool occluded(Vec3 origin, Vec3 dir) const;

  const MesoStructure& structure() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Generates the BTF of a meso-structure. Multithreaded (TBB); `show_progress` draws a bar.
Btf generate_btf(const MesoStructure& meso, const BtfParams& params, bool show_progress = false);

/// Stage-cache key of a material's BTF: generator and archive versions, kBtfMaterialsVersion,
/// the material name, every parameter and the built geometry and BRDFs.
Hash128 btf_cache_key(const MesoStructure& meso, const BtfParams& params);

struct BtfStageResult {
  Btf btf;
  Hash128 key;
  bool cache_hit = false;
  double seconds = 0;           ///< this call (load on a hit, generate + store + load on a miss)
  double generate_seconds = 0;  ///< ray tracing alone (0 on a hit)
  std::filesystem::path cache_file;
};

/// The named material's BTF from the stage cache (stage "btf"), generated on a miss.
BtfStageResult generate_btf_cached(std::string_view material, const BtfParams& params,
                                   StageCache& cache, CacheMode mode = CacheMode::kUse,
                                   bool show_progress = false);

}  // namespace prt
