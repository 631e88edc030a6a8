#pragma once
// G-buffer: what the BTF shading stage needs per pixel, from one Embree primary ray through
// every pixel centre (docs/rendering.md, "G-buffer").
//
// Layout (structure of arrays, row-major pixels, row 0 at the top, pixel index i = y * width +
// x; every array is a plain float or int32 buffer, ready for clCreateBuffer as is):
//
//   array        type      per pixel  hit                                  miss
//   triangle     int32     1          triangle index into mesh.indices/3   -1
//   part         int32     1          mesh.part_of(triangle)               -1
//   bary         float     2          (b1, b2): weights of the triangle's  (0, 0)
//                                     2nd and 3rd vertex; b0 = 1 - b1 - b2
//   uv           float     2          interpolated mesh UV (mesh.uvs       (0, 0)
//                                     already include the part's uv_scale,
//                                     see build_scene); (0, 0) without UVs
//   view_local   float     4          (e.t, e.b, e.n, 0): unit direction   (0, 0, 0, 0)
//                                     from the hit point to the eye in the
//                                     interpolated local frame
//   normal       float     4          (n, 0): world shading normal (the    (0, 0, 0, 0)
//                                     frame's n)
//   direction    float     4          (d, 0): unit world direction of the ray (also for hits);
//                                     for misses it is the environment lookup direction
//   depth        float     1          distance from the eye along the ray  +inf
//
// Four-float entries are padded RGB-like (x, y, z, 0) so kernels can load them as float4.
//
// Local frame at a hit: the three vertex frames (Mesh::frame, the frames T was computed in)
// are interpolated with the barycentrics and re-orthonormalised: n = normalize(sum b_i n_i),
// t = sum b_i t_i made orthogonal to n and normalised (Gram-Schmidt), b = n x t. Where the
// interpolated tangent degenerates (opposite vertex tangents), LocalFrame::from_normal is used.
// e is not clamped: near silhouettes the shading normal can face away from the eye (e.z < 0)
// and a ray hitting a triangle's back gives e.z < 0 too; the shading stage decides what to do.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <vector>

#include "prtlab/geometry/camera.h"
#include "prtlab/geometry/mesh.h"
#include "prtlab/image/image_io.h"

namespace prt {

struct GBuffer {
  int width = 0;
  int height = 0;
  Vec3d eye{0.0};
  std::vector<std::int32_t> triangle;
  std::vector<std::int32_t> part;
  std::vector<float> bary;        ///< 2 per pixel
  std::vector<float> uv;          ///< 2 per pixel
  std::vector<float> view_local;  ///< 4 per pixel
  std::vector<float> normal;      ///< 4 per pixel
  std::vector<float> direction;   ///< 4 per pixel
  std::vector<float> depth;       ///< 1 per pixel

  std::size_t pixel_count() const { return static_cast<std::size_t>(width) * height; }
  std::size_t index(int x, int y) const { return static_cast<std::size_t>(y) * width + x; }
  bool hit(int x, int y) const { return triangle[index(x, y)] >= 0; }
  std::size_t hit_count() const;
  /// Resize every array for width x height and fill it with the miss values.
  void reset(int width, int height);
};

/// How GBufferTracer finds what each pixel sees (docs/rendering.md "G-buffer"). All give the
/// same G-buffer, to rounding (tests/core/gbuffer_test.cpp compares them).
enum class PrimaryRays {
  /// Embree 16-wide packets of 4 x 4 pixels with coherent flags; only pixels inside the
  /// projection of the mesh's bounding box are traced (the others are known misses).
  kPackets,
  /// One rtcIntersect1 per pixel, every pixel: the reference.
  kSingle,
  /// The mesh's triangles rasterised (perspective-correct barycentrics, nearest along the ray),
  /// so the cost follows the triangles and the pixels they cover; the same triangle as a ray
  /// at every pixel centre not within rounding of an edge. Traces packets instead when a
  /// vertex lies at or behind the eye's plane.
  kRaster,
};

/// Primary-ray tracer of a mesh: builds the Embree BVH and the per-vertex frames once, then
/// traces G-buffers for any number of cameras. Thread-safe for trace(); move-only.
class GBufferTracer {
 public:
  /// The mesh must have triangles; normals (and tangents) are computed on a copy when absent.
  explicit GBufferTracer(const Mesh& mesh);
  ~GBufferTracer();
  GBufferTracer(GBufferTracer&&) noexcept;
  GBufferTracer& operator=(GBufferTracer&&) noexcept;
  GBufferTracer(const GBufferTracer&) = delete;
  GBufferTracer& operator=(const GBufferTracer&) = delete;

  /// One ray through every pixel centre, in parallel over 16 x 16 tiles (TBB).
  GBuffer trace(const Camera& camera, PrimaryRays rays = PrimaryRays::kPackets) const;
  /// The same into `out`, whose arrays are reused when the image size is unchanged (every
  /// field of every pixel is overwritten): a frame loop then allocates nothing.
  void trace(const Camera& camera, GBuffer& out, PrimaryRays rays = PrimaryRays::kPackets) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Convenience: build the tracer and trace one camera.
GBuffer render_gbuffer(const Mesh& mesh, const Camera& camera);

/// Debug pictures of a G-buffer (background black).
enum class GBufferView {
  kNormal,     ///< world shading normal, n * 0.5 + 0.5
  kUv,         ///< (frac(u), frac(v), 0)
  kUvChecker,  ///< 4 x 4 checker per UV unit (one BTF tile), tinted by (frac u, frac v)
  kViewLocal,  ///< local view direction e * 0.5 + 0.5
  kPart,       ///< a distinct colour per part
};
/// The picture as an image (values in [0, 1]).
RgbImage gbuffer_image(const GBuffer& gbuffer, GBufferView view);
/// Writes the picture as an 8-bit PNG without tone mapping (values in [0, 1], gamma 1).
void write_gbuffer_png(const GBuffer& gbuffer, GBufferView view, const std::filesystem::path& file);

}  // namespace prt
