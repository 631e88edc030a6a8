#include "prtlab/render/biscale_reference.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>

#include "prtlab/base/error.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/transfer/visibility.h"

namespace prt {
namespace {

// SplitMix64 (Steele, Lea and Flood 2014): a tiny, well-mixed generator; one stream per pixel.
struct SplitMix64 {
  std::uint64_t state;
  std::uint64_t next() {
    std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
};

// The mesh with normals and tangents, completed on a copy as GBufferTracer does, so the frames
// here are the ones the G-buffer was traced with.
struct FramedMesh {
  Mesh completed;
  const Mesh* mesh = nullptr;
  std::vector<Vec3d> frame_t, frame_n;

  explicit FramedMesh(const Mesh& input) : mesh(&mesh_with_frames(input, completed)) {
    frame_t.resize(mesh->vertex_count());
    frame_n.resize(mesh->vertex_count());
    for (std::size_t v = 0; v < mesh->vertex_count(); ++v) {
      const LocalFrame f = mesh->frame(v);
      frame_t[v] = f.t;
      frame_n[v] = f.n;
    }
  }
};

struct HitPoint {
  Vec3d position{0.0};
  LocalFrame frame;
  Vec3d geometric_normal{0.0, 0.0, 1.0};  ///< turned to the side of frame.n
  Vec2 uv{0.f};
  Vec3 view_local{0.f};
  int part = 0;
};

// The pixel's hit: position on the flat triangle and the G-buffer's frame (gbuffer.cpp's
// construction, repeated here because the G-buffer stores n but not t).
HitPoint hit_point(const GBuffer& g, const FramedMesh& fm, std::size_t i) {
  const Mesh& mesh = *fm.mesh;
  const auto tri = static_cast<std::size_t>(g.triangle[i]);
  const std::uint32_t* v = &mesh.indices[3 * tri];
  const double b1 = g.bary[2 * i], b2 = g.bary[2 * i + 1], b0 = 1.0 - b1 - b2;
  HitPoint h;
  const Vec3d p0(mesh.positions[v[0]]), p1(mesh.positions[v[1]]), p2(mesh.positions[v[2]]);
  h.position = b0 * p0 + b1 * p1 + b2 * p2;
  Vec3d n = b0 * fm.frame_n[v[0]] + b1 * fm.frame_n[v[1]] + b2 * fm.frame_n[v[2]];
  const double nl = glm::length(n);
  const Vec3d dir(g.direction[4 * i], g.direction[4 * i + 1], g.direction[4 * i + 2]);
  if (!(nl > 1e-12)) {
    n = glm::cross(fm.frame_n[v[1]] - fm.frame_n[v[0]], fm.frame_n[v[2]] - fm.frame_n[v[0]]);
    n = glm::length(n) > 0 ? glm::normalize(n) : -dir;
  } else {
    n /= nl;
  }
  const Vec3d t_sum = b0 * fm.frame_t[v[0]] + b1 * fm.frame_t[v[1]] + b2 * fm.frame_t[v[2]];
  h.frame = LocalFrame::from_normal_tangent(n, t_sum);
  Vec3d ng = glm::cross(p1 - p0, p2 - p0);
  const double ngl = glm::length(ng);
  ng = ngl > 0 ? ng / ngl : h.frame.n;
  h.geometric_normal = glm::dot(ng, h.frame.n) < 0 ? -ng : ng;
  h.uv = Vec2(g.uv[2 * i], g.uv[2 * i + 1]);
  h.view_local = Vec3(g.view_local[4 * i], g.view_local[4 * i + 1], g.view_local[4 * i + 2]);
  h.part = g.part[i];
  return h;
}

const Btf& part_btf(std::span<const std::shared_ptr<const Btf>> part_btfs, int part) {
  if (part < 0 || static_cast<std::size_t>(part) >= part_btfs.size() ||
      !part_btfs[static_cast<std::size_t>(part)]) {
    throw ParameterError(
        fmt::format("bi-scale reference: part {} has no BTF ({} part BTFs were given)", part,
                    part_btfs.size()));
  }
  return *part_btfs[static_cast<std::size_t>(part)];
}

int light_side_of(const Btf& btf) {
  const int s = btf.light_side();
  PRT_CHECK(s * s == btf.light_count(), "BTF light count {} is not a square", btf.light_count());
  return s;
}

void check_gbuffer(const GBuffer& g, const Mesh& mesh) {
  const std::size_t n = g.pixel_count();
  if (g.triangle.size() != n || g.bary.size() != 2 * n || g.uv.size() != 2 * n ||
      g.view_local.size() != 4 * n || g.direction.size() != 4 * n || g.part.size() != n) {
    throw ParameterError("bi-scale reference: the G-buffer's arrays do not match its size");
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (g.triangle[i] >= 0 && static_cast<std::size_t>(g.triangle[i]) >= mesh.triangle_count()) {
      throw ParameterError(fmt::format(
          "bi-scale reference: the G-buffer hits triangle {} but the mesh has {} (traced from "
          "another mesh?)",
          g.triangle[i], mesh.triangle_count()));
    }
  }
}

Vec3d pixel_direction(const GBuffer& g, std::size_t i) {
  return {g.direction[4 * i], g.direction[4 * i + 1], g.direction[4 * i + 2]};
}

}  // namespace

RadianceFunction cubemap_lookup(const Cubemap& cubemap) {
  auto shared = std::make_shared<const Cubemap>(cubemap);
  return [shared](const Vec3d& d) { return shared->radiance[shared->layout.pixel_of(d)]; };
}

RadianceFunction latlong_lookup(const LatLongImage& image) {
  if (image.width <= 0 || image.height <= 0 ||
      image.texels.size() != static_cast<std::size_t>(image.width) * image.height) {
    throw ParameterError("latlong_lookup: the image is empty or its texels do not match its size");
  }
  auto shared = std::make_shared<const LatLongImage>(image);
  return [shared](const Vec3d& d) {
    const Vec2d uv = direction_to_latlong(d);
    const int col = std::clamp(static_cast<int>(uv.x * shared->width), 0, shared->width - 1);
    const int row = std::clamp(static_cast<int>(uv.y * shared->height), 0, shared->height - 1);
    return shared->at(col, row);
  };
}

Cubemap cubemap_from_radiance(int resolution, const RadianceFunction& radiance, int supersampling) {
  if (supersampling < 1 || supersampling > 64)
    throw ParameterError(
        fmt::format("cubemap_from_radiance: supersampling {} outside [1, 64]", supersampling));
  Cubemap cubemap(resolution);
  const SupersampledCubemap sub(resolution, supersampling);
  const auto per_pixel = static_cast<std::size_t>(sub.subrays_per_pixel());
  tbb::parallel_for(0, cubemap.layout.pixel_count(), [&](int k) {
    Vec3d sum(0.0);
    double area = 0;
    for (std::size_t r = k * per_pixel; r < (k + 1) * per_pixel; ++r) {
      const double w = sub.solid_angles()[r];
      sum += w * Vec3d(radiance(glm::normalize(sub.direction(r))));
      area += w;
    }
    cubemap.radiance[static_cast<std::size_t>(k)] = Rgb(sum / area);
  });
  return cubemap;
}

Rgb btf_eval_continuous(const Btf& btf, Vec2 uv, Vec3 view_local, const Vec3d& light_local,
                        TexelFilter filter) {
  const double len = glm::length(light_local);
  if (!(len > 0) || !(light_local.z > 0)) return Rgb(0.f);
  const Vec3d w = light_local / len;
  std::vector<Rgb> b(static_cast<std::size_t>(btf.light_count()));
  btf.eval_lights(uv, view_local, b, filter);
  const HemisphereGrid grid(light_side_of(btf));
  const std::vector<double> projected = grid.projected_solid_angles();
  const BtfViewSamples ls = btf_view_samples(grid.side(), Vec3(w));
  Vec3d c(0.0);
  for (int k = 0; k < 4; ++k) {
    const int j = ls.view[k];  // btf_view_samples serves any grid of this kind
    // The stored value carries the cell-mean cosine P_j / Omega_j (btf.h "Units").
    const double mean_cos = projected[static_cast<std::size_t>(j)] / grid.cell_solid_angle();
    c += static_cast<double>(ls.weight[k]) * Vec3d(b[j]) / mean_cos;
  }
  return Rgb(c * w.z);
}

BiscaleReference render_biscale_reference(const GBuffer& gbuffer, const Mesh& mesh,
                                          std::span<const std::shared_ptr<const Btf>> part_btfs,
                                          const RadianceFunction& environment,
                                          const BiscaleReferenceOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  if (options.samples_side < 2 || options.samples_side > 256 || options.samples_side % 2 != 0) {
    throw ParameterError(fmt::format(
        "bi-scale reference: samples_side {} must be even and in [2, 256] (strata are paired "
        "for the noise estimate)",
        options.samples_side));
  }
  if (!environment) throw ParameterError("bi-scale reference: no environment radiance function");
  check_gbuffer(gbuffer, mesh);
  const FramedMesh fm(mesh);
  const EmbreeScene scene(*fm.mesh, options.ray_offset_relative);
  const double offset = scene.ray_offset();
  const int side = options.samples_side;
  const int samples = side * side;

  // Cell-mean cosines of the parts' BTF light grids (btf.h "Units"; built once).
  std::vector<std::vector<double>> mean_cos(part_btfs.size());
  if (!options.btf) {
    for (std::size_t p = 0; p < mean_cos.size(); ++p) {
      if (!part_btfs[p]) continue;
      const HemisphereGrid grid(light_side_of(*part_btfs[p]));
      mean_cos[p] = grid.projected_solid_angles();
      for (double& m : mean_cos[p]) m /= grid.cell_solid_angle();
    }
  }

  BiscaleReference out;
  out.radiance = RgbImage(gbuffer.width, gbuffer.height);
  out.standard_error = RgbImage(gbuffer.width, gbuffer.height);
  out.samples_per_pixel = samples;
  std::atomic<std::uint64_t> rays{0};
  tbb::enumerable_thread_specific<std::vector<Rgb>> b_tls;

  tbb::parallel_for(
      tbb::blocked_range<int>(0, gbuffer.height), [&](const tbb::blocked_range<int>& rows) {
        std::vector<Rgb>& b = b_tls.local();
        std::vector<Vec3d> c;
        std::uint64_t local_rays = 0;
        for (int y = rows.begin(); y != rows.end(); ++y) {
          for (int x = 0; x < gbuffer.width; ++x) {
            const std::size_t i = gbuffer.index(x, y);
            if (gbuffer.triangle[i] < 0) {
              out.radiance.pixels[i] =
                  options.background ? environment(pixel_direction(gbuffer, i)) : Rgb(0.f);
              continue;
            }
            const HitPoint h = hit_point(gbuffer, fm, i);
            const Btf* btf = nullptr;
            if (!options.btf) {
              btf = &part_btf(part_btfs, h.part);
              const std::vector<double>& mc = mean_cos[static_cast<std::size_t>(h.part)];
              // b / (cell-mean cosine) at the light samples for this pixel's texel(s) and view.
              b.resize(static_cast<std::size_t>(btf->light_count()));
              btf->eval_lights(h.uv, h.view_local, b, options.filter);
              c.resize(b.size());
              for (std::size_t j = 0; j < b.size(); ++j) c[j] = Vec3d(b[j]) / mc[j];
            }
            SplitMix64 rng{options.seed * 0x9e3779b97f4a7c15ull ^
                           (static_cast<std::uint64_t>(i) + 1)};
            rng.next();
            const Vec3d origin = h.position + offset * h.geometric_normal;
            // One sample: pi * (b / cos) * L * V, with pdf cos / pi.
            auto sample = [&](double a, double bb) -> Vec3d {
              const Vec2d disk = square_to_disk_concentric({a, bb});
              const double z2 = 1.0 - glm::dot(disk, disk);
              if (!(z2 > 0)) return Vec3d(0.0);  // the rim of the disk: measure zero
              const Vec3d l(disk.x, disk.y, std::sqrt(z2));
              const Vec3d w = h.frame.to_world(l);
              if (!(glm::dot(w, h.geometric_normal) > 0)) return Vec3d(0.0);  // own triangle
              ++local_rays;
              if (scene.occluded(origin, w)) return Vec3d(0.0);
              Vec3d b_over_cos(0.0);
              if (options.btf) {
                b_over_cos = Vec3d(options.btf(h.part, h.uv, h.view_local, l)) / l.z;
              } else {
                const BtfViewSamples ls = btf_view_samples(light_side_of(*btf), Vec3(l));
                for (int k = 0; k < 4; ++k)
                  b_over_cos +=
                      static_cast<double>(ls.weight[k]) * c[static_cast<std::size_t>(ls.view[k])];
              }
              return kPi * b_over_cos * Vec3d(environment(w));
            };
            // Variance of a one-sample-per-stratum estimate by collapsed strata (Cochran,
            // Sampling Techniques, ch. 5A): horizontally adjacent strata form pairs,
            // Var(mean) ~ (1/K^2) sum over pairs (f_a - f_b)^2. It overestimates the variance by
            // the spread of the stratum means within each pair, never underestimates it.
            Vec3d sum(0.0), pair_sq(0.0), first(0.0);
            for (int sy = 0; sy < side; ++sy) {
              for (int sx = 0; sx < side; ++sx) {
                const double a = (sx + rng.uniform()) / side, bb = (sy + rng.uniform()) / side;
                const Vec3d f = sample(a, bb);
                sum += f;
                if (sx % 2 == 0) {
                  first = f;
                } else {
                  pair_sq += (f - first) * (f - first);
                }
              }
            }
            const double k = samples;
            out.radiance.pixels[i] = Rgb(sum / k);
            out.standard_error.pixels[i] = Rgb(glm::sqrt(pair_sq) / k);
          }
        }
        rays.fetch_add(local_rays, std::memory_order_relaxed);
      });
  out.rays_traced = rays.load();
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

RgbImage render_pointwise_transfer(const GBuffer& gbuffer, const Mesh& mesh,
                                   std::span<const std::shared_ptr<const Btf>> part_btfs,
                                   const Cubemap& environment,
                                   const PointwiseTransferOptions& options) {
  if (options.supersampling < 1 || options.supersampling > 15) {
    throw ParameterError(
        fmt::format("pointwise transfer: supersampling {} outside [1, 15]", options.supersampling));
  }
  check_gbuffer(gbuffer, mesh);
  const FramedMesh fm(mesh);
  const EmbreeScene scene(*fm.mesh, options.ray_offset_relative);
  const CubemapLayout& layout = environment.layout;
  const SupersampledCubemap dirs(layout.resolution(), options.supersampling);
  const int n = layout.pixel_count();
  const double s2 = static_cast<double>(options.supersampling) * options.supersampling;
  // L_k = radiance_k * solidAngle_k, as the relight's light vector (cubemap.h), in double.
  std::vector<Vec3d> light(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k)
    light[static_cast<std::size_t>(k)] =
        Vec3d(environment.radiance[static_cast<std::size_t>(k)]) * layout.solid_angle(k);
  std::vector<std::unique_ptr<HemisphereGrid>> grids(part_btfs.size());
  for (std::size_t p = 0; p < grids.size(); ++p) {
    if (part_btfs[p]) grids[p] = std::make_unique<HemisphereGrid>(light_side_of(*part_btfs[p]));
  }

  RgbImage out(gbuffer.width, gbuffer.height);
  struct Scratch {
    std::vector<std::uint8_t> counts;
    std::vector<Vec3d> local_radiance;
    std::vector<Rgb> b;
  };
  tbb::enumerable_thread_specific<Scratch> scratch_tls;
  tbb::parallel_for(
      tbb::blocked_range<int>(0, gbuffer.height), [&](const tbb::blocked_range<int>& rows) {
        Scratch& s = scratch_tls.local();
        s.counts.resize(static_cast<std::size_t>(n));
        for (int y = rows.begin(); y != rows.end(); ++y) {
          for (int x = 0; x < gbuffer.width; ++x) {
            const std::size_t i = gbuffer.index(x, y);
            if (gbuffer.triangle[i] < 0) {
              out.pixels[i] = options.background
                                  ? environment.radiance[static_cast<std::size_t>(
                                        layout.pixel_of(pixel_direction(gbuffer, i)))]
                                  : Rgb(0.f);
              continue;
            }
            const HitPoint h = hit_point(gbuffer, fm, i);
            const Btf& btf = part_btf(part_btfs, h.part);
            const HemisphereGrid& grid = *grids[static_cast<std::size_t>(h.part)];
            scene.visibility(dirs, h.position, h.frame.n, s.counts);
            s.local_radiance.assign(static_cast<std::size_t>(grid.cell_count()), Vec3d(0.0));
            for (int k = 0; k < n; ++k) {
              const std::uint8_t count = s.counts[static_cast<std::size_t>(k)];
              if (count == 0) continue;
              Vec3d l = h.frame.to_local(layout.direction(k));
              if (!(l.z > 0.0)) {
                // transfer_matrix.h: a pixel centre on or below the tangent plane with unblocked
                // sub-rays goes to the rim cell at its azimuth.
                const double hl = std::sqrt(l.x * l.x + l.y * l.y);
                if (!(hl > 0.0)) continue;
                l = Vec3d(l.x / hl, l.y / hl, 1e-9);
              }
              const int j = grid.cell_of(l);
              PRT_CHECK(j >= 0, "pixel {} has no local cell", k);
              s.local_radiance[static_cast<std::size_t>(j)] +=
                  (count / s2) * light[static_cast<std::size_t>(k)];
            }
            s.b.resize(static_cast<std::size_t>(btf.light_count()));
            btf.eval_lights(h.uv, h.view_local, s.b, options.filter);
            Vec3d sum(0.0);
            for (std::size_t j = 0; j < s.b.size(); ++j) sum += Vec3d(s.b[j]) * s.local_radiance[j];
            out.pixels[i] = Rgb(sum);
          }
        }
      });
  return out;
}

}  // namespace prt
