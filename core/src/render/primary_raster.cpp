#include "render/primary_raster.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace prt {
namespace {

// Rows per strip: a strip is one task and owns its pixels, so no two tasks write one pixel.
constexpr int kStripRows = 8;

struct Projected {
  double x = 0, y = 0;  // pixel coordinates: pixel (i, j)'s centre is (i, j)
  double inv_z = 0;     // 1 / depth along the view axis
};

// The edge function of (a, b) as e(x, y) = A x + B y + C, its coefficients computed with the
// endpoints in the order of their vertex index whatever the triangle's winding, so that the two
// triangles of a shared edge evaluate the same value with opposite signs, bit for bit: no pixel
// centre falls between them.
struct Edge {
  double a = 0, b = 0, c = 0;
  double at(double x, double y) const { return a * x + b * y + c; }
};

inline Edge edge(const Projected* v, std::uint32_t ia, std::uint32_t ib) {
  const bool swap = ia > ib;
  const Projected& p = v[swap ? ib : ia];
  const Projected& q = v[swap ? ia : ib];
  Edge e{p.y - q.y, q.x - p.x, 0.0};
  e.c = -(e.a * p.x + e.b * p.y);
  if (swap) e = {-e.a, -e.b, -e.c};
  return e;
}

int clamp_to_int(double v, int lo, int hi) {
  return static_cast<int>(std::clamp(v, static_cast<double>(lo), static_cast<double>(hi)));
}

}  // namespace

bool rasterize_primary(std::span<const Vec3> positions, std::span<const std::uint32_t> indices,
                       const Camera& camera, const CameraBasis& basis, PrimaryHits& hits) {
  const int width = camera.width, height = camera.height;
  const double sx_scale = basis.tan_half_fov_y * basis.aspect;
  const double sy_scale = basis.tan_half_fov_y;

  // Every vertex in front of the eye's plane, with a margin relative to its distance.
  std::vector<Projected> v(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const Vec3d q = Vec3d(positions[i]) - camera.eye;
    const double z = glm::dot(q, basis.forward);
    if (!(z > 1e-9 * (1.0 + glm::length(q)))) return false;
    // Pixel x's ray has sx = 2 (x + 0.5) / W - 1; row y's has sy = 1 - 2 (y + 0.5) / H.
    const double sx = glm::dot(q, basis.right) / (z * sx_scale);
    const double sy = glm::dot(q, basis.up) / (z * sy_scale);
    v[i] = {(sx + 1.0) * 0.5 * width - 0.5, (1.0 - sy) * 0.5 * height - 0.5, 1.0 / z};
  }

  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  // Sized here, cleared by the strip that owns the rows (in parallel, while they are in cache).
  hits.triangle.resize(pixels);
  hits.b1.resize(pixels);
  hits.b2.resize(pixels);
  hits.t.resize(pixels);
  hits.view_depth.resize(pixels);
  std::vector<double>& nearest = hits.view_depth;

  // Triangles binned by the strips their rows reach (counting sort: the bins in one array).
  const int strips = (height + kStripRows - 1) / kStripRows;
  const std::size_t triangles = indices.size() / 3;
  std::vector<int> first_strip(triangles), last_strip(triangles, -1);
  std::vector<std::uint32_t> count(static_cast<std::size_t>(strips) + 1, 0);
  for (std::size_t t = 0; t < triangles; ++t) {
    const Projected &a = v[indices[3 * t]], &b = v[indices[3 * t + 1]], &c = v[indices[3 * t + 2]];
    const double lo = std::ceil(std::min({a.y, b.y, c.y}));
    const double hi = std::floor(std::max({a.y, b.y, c.y}));
    if (hi < 0 || lo > height - 1 || std::max({a.x, b.x, c.x}) < 0 ||
        std::min({a.x, b.x, c.x}) > width - 1)
      continue;
    first_strip[t] = static_cast<int>(std::max(lo, 0.0)) / kStripRows;
    last_strip[t] = static_cast<int>(std::min(hi, height - 1.0)) / kStripRows;
    for (int s = first_strip[t]; s <= last_strip[t]; ++s) ++count[static_cast<std::size_t>(s) + 1];
  }
  for (int s = 0; s < strips; ++s) count[s + 1] += count[s];
  std::vector<std::uint32_t> bin(count[static_cast<std::size_t>(strips)]);
  {
    std::vector<std::uint32_t> fill(count.begin(), count.end() - 1);
    for (std::size_t t = 0; t < triangles; ++t)
      for (int s = first_strip[t]; s <= last_strip[t]; ++s)
        bin[fill[s]++] = static_cast<std::uint32_t>(t);
  }

  tbb::parallel_for(
      tbb::blocked_range<int>(0, strips, 1),
      [&](const tbb::blocked_range<int>& range) {
        for (int s = range.begin(); s != range.end(); ++s) {
          const int y0 = s * kStripRows, y1 = std::min(height, y0 + kStripRows);
          const std::size_t p0 = static_cast<std::size_t>(y0) * width,
                            p1 = static_cast<std::size_t>(y1) * width;
          std::fill(hits.triangle.begin() + p0, hits.triangle.begin() + p1, -1);
          std::fill(nearest.begin() + p0, nearest.begin() + p1,
                    std::numeric_limits<double>::infinity());
          for (std::uint32_t k = count[s]; k < count[s + 1]; ++k) {
            const std::uint32_t t = bin[k];
            const std::uint32_t i0 = indices[3 * t], i1 = indices[3 * t + 1],
                                i2 = indices[3 * t + 2];
            const Projected &a = v[i0], &b = v[i1], &c = v[i2];
            const Edge e0 = edge(v.data(), i1, i2), e1 = edge(v.data(), i2, i0),
                       e2 = edge(v.data(), i0, i1);
            const double area = e0.at(a.x, a.y);
            // Edge-on: its projection is a segment, which no pixel centre's ray meets but by
            // grazing it.
            if (!(std::abs(area) > 0)) continue;
            // Clamped before the conversion: a vertex near the eye's plane projects far away.
            const int ya = clamp_to_int(std::ceil(std::min({a.y, b.y, c.y})), y0, y1 - 1);
            const int yb = clamp_to_int(std::floor(std::max({a.y, b.y, c.y})), y0 - 1, y1 - 1);
            const int xa = clamp_to_int(std::ceil(std::min({a.x, b.x, c.x})), 0, width - 1);
            const int xb = clamp_to_int(std::floor(std::max({a.x, b.x, c.x})), -1, width - 1);
            const double sign = area > 0 ? 1.0 : -1.0;
            for (int y = ya; y <= yb; ++y) {
              // The columns where every edge function has the area's sign, from each edge's
              // crossing of the row, widened by a pixel each side: the edge functions below
              // decide every pixel, the span only spares testing those certainly outside.
              double lo = xa, hi = xb;
              for (const Edge* e : {&e0, &e1, &e2}) {
                const double ea = sign * e->a, er = sign * (e->b * y + e->c);  // ea x + er >= 0
                if (ea > 0)
                  lo = std::max(lo, std::floor(-er / ea) - 1.0);
                else if (ea < 0)
                  hi = std::min(hi, std::ceil(-er / ea) + 1.0);
                else if (er < 0)
                  hi = lo - 1.0;
              }
              if (!(lo <= hi)) continue;
              const int x_lo = static_cast<int>(lo), x_hi = static_cast<int>(hi);
              for (int x = x_lo; x <= x_hi; ++x) {
                const double w0 = e0.at(x, y), w1 = e1.at(x, y), w2 = e2.at(x, y);
                const bool inside =
                    area > 0 ? (w0 >= 0 && w1 >= 0 && w2 >= 0) : (w0 <= 0 && w1 <= 0 && w2 <= 0);
                if (!inside) continue;
                // Perspective-correct: screen weights over depth, normalised.
                const double p0 = w0 * a.inv_z, p1 = w1 * b.inv_z, p2 = w2 * c.inv_z;
                const double sum = p0 + p1 + p2;
                if (!(std::abs(sum) > 0)) continue;
                const double z = (w0 + w1 + w2) / sum;  // depth along the view axis
                const std::size_t i = static_cast<std::size_t>(y) * width + x;
                if (z > nearest[i] ||
                    (z == nearest[i] && static_cast<std::int32_t>(t) > hits.triangle[i]))
                  continue;
                nearest[i] = z;
                hits.triangle[i] = static_cast<std::int32_t>(t);
                hits.b1[i] = static_cast<float>(p1 / sum);
                hits.b2[i] = static_cast<float>(p2 / sum);
              }
            }
          }
          // Distance along the unit ray: the view-axis depth times the ray's length when its
          // forward component is 1.
          for (int y = y0; y < y1; ++y) {
            const double sy = (1.0 - 2.0 * (y + 0.5) / height) * sy_scale;
            for (int x = 0; x < width; ++x) {
              const std::size_t i = static_cast<std::size_t>(y) * width + x;
              if (hits.triangle[i] < 0) continue;
              const double sx = (2.0 * (x + 0.5) / width - 1.0) * sx_scale;
              hits.t[i] = static_cast<float>(nearest[i] * std::sqrt(1.0 + sx * sx + sy * sy));
            }
          }
        }
      },
      tbb::simple_partitioner());
  return true;
}

}  // namespace prt
