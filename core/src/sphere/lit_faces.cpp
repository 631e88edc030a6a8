#include "prtlab/sphere/lit_faces.h"

namespace prt {

std::uint32_t lit_faces(std::span<const Rgb> light) {
  if (light.size() % kCubeFaces != 0) return kAllFaces;
  const std::size_t per_face = light.size() / kCubeFaces;
  std::uint32_t lit = 0;
  for (int f = 0; f < kCubeFaces; ++f) {
    for (const Rgb& v : light.subspan(f * per_face, per_face)) {
      if (!(v.x == 0.0f && v.y == 0.0f && v.z == 0.0f)) {
        lit |= 1u << f;
        break;
      }
    }
  }
  return lit;
}

}  // namespace prt
