#pragma once
// Private to prtlab_core: an Embree device with one committed triangle-mesh scene. Visibility
// (visibility.cpp), the G-buffer (gbuffer.cpp), the BTF meso-structure tracer
// (btf_generator.cpp) and the path-traced reference all trace the same kind of scene; building
// it in one place keeps the flags that matter for correctness identical everywhere: robust
// traversal (watertight: no ray slips through a shared edge) and high build quality.
#include <embree3/rtcore.h>

#include <cstdint>
#include <memory>
#include <span>

#include "prtlab/base/types.h"

namespace prt {

class EmbreeTriangleScene {
 public:
  /// Throws prt::Error with Embree's first error message when the device, the buffers or the
  /// BVH cannot be built; ParameterError when there are no triangles.
  EmbreeTriangleScene(std::span<const Vec3> positions, std::span<const std::uint32_t> indices);
  ~EmbreeTriangleScene();
  EmbreeTriangleScene(EmbreeTriangleScene&&) noexcept;
  EmbreeTriangleScene& operator=(EmbreeTriangleScene&&) noexcept;
  EmbreeTriangleScene(const EmbreeTriangleScene&) = delete;
  EmbreeTriangleScene& operator=(const EmbreeTriangleScene&) = delete;

  /// The committed scene, for rtcIntersect / rtcOccluded (thread-safe for queries).
  RTCScene scene() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace prt
