#include "prtlab/render/btf_shading.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <map>
#include <optional>

#include "prtlab/base/error.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/opencl/cl_runtime.h"
#include "render/shading_program.h"

namespace prt {

static_assert(sizeof(Rgb) == 3 * sizeof(float), "Rgb must be three packed floats");

namespace {

constexpr std::size_t kWorkGroup = kShadingWorkGroup;

std::size_t part_count(const Mesh& mesh) {
  std::size_t parts = 1;
  for (const auto p : mesh.triangle_part) parts = std::max<std::size_t>(parts, p + 1u);
  return parts;
}

// The background pixel a miss shows, or `black` (a pixel index past the cubemap) without one.
int background_pixel(const float* direction, const CubemapLayout* layout, int black) {
  const Vec3d d(direction[0], direction[1], direction[2]);
  if (!layout || !(d.x != 0.0 || d.y != 0.0 || d.z != 0.0) || !std::isfinite(d.x + d.y + d.z))
    return black;
  return layout->pixel_of(d);
}

double event_ms(ClContext& ctx, cl::Event& event, const std::string& name) {
  return event_milliseconds(event, ctx.info().device_name, "timing of kernel " + name);
}

}  // namespace

std::vector<const CompressedMaterial*> ShadingMaterials::parts() const {
  std::vector<const CompressedMaterial*> out;
  for (const auto& m : part_material) out.push_back(m.get());
  return out;
}

MaterialLightBasis validate_materials(const ShadingMaterials& materials, const Mesh& mesh) {
  const std::size_t parts = part_count(mesh);
  if (materials.part_material.size() < parts)
    throw ParameterError(
        fmt::format("BTF shading: the mesh has {} parts but {} materials were given", parts,
                    materials.part_material.size()));
  for (std::size_t p = 0; p < materials.part_material.size(); ++p)
    if (!materials.part_material[p])
      throw ParameterError(fmt::format("BTF shading: part {} has no material", p));
  const CompressedMaterial& first = *materials.part_material.front();
  for (std::size_t p = 1; p < materials.part_material.size(); ++p) {
    const CompressedMaterial& m = *materials.part_material[p];
    if (m.backend() != first.backend())
      throw ParameterError(fmt::format(
          "BTF shading: part {} uses material '{}', part 0 '{}': a scene shades with one "
          "material backend",
          p, m.backend(), first.backend()));
    if (m.light_basis() != first.light_basis())
      throw ParameterError(fmt::format(
          "BTF shading: part {}'s material ('{}') takes light in {}, part 0's in {} (generate "
          "every BTF with light_side = the scene's local_grid)",
          p, m.sampling().material, m.light_basis().describe(), first.light_basis().describe()));
  }
  return first.light_basis();
}

RgbImage shade_frame_reference(const GBuffer& g, const Mesh& mesh,
                               const ShadingMaterials& materials, const LocalRadiance& radiance,
                               const Cubemap* background, const ShadingOptions& options) {
  const MaterialLightBasis basis = validate_materials(materials, mesh);
  check_light_basis(basis, radiance, mesh.positions.size(), "BTF shading");
  const Cubemap* bg = options.background ? background : nullptr;
  const int m = radiance.dim;
  RgbImage image(g.width, g.height);
  tbb::parallel_for(tbb::blocked_range<int>(0, g.height), [&](const tbb::blocked_range<int>& rows) {
    std::vector<Rgb> lstar(static_cast<std::size_t>(m));
    for (int y = rows.begin(); y < rows.end(); ++y) {
      for (int x = 0; x < g.width; ++x) {
        const std::size_t i = g.index(x, y);
        const std::int32_t tri = g.triangle[i];
        if (tri < 0) {
          const int k = background_pixel(&g.direction[4 * i], bg ? &bg->layout : nullptr, -1);
          image.at(x, y) = k < 0 ? Rgb(0.0f) : bg->radiance[k];
          continue;
        }
        const std::uint32_t* v = &mesh.indices[3 * static_cast<std::size_t>(tri)];
        const float w1 = g.bary[2 * i], w2 = g.bary[2 * i + 1], w0 = 1.0f - w1 - w2;
        const auto l0 = radiance.vertex(v[0]), l1 = radiance.vertex(v[1]),
                   l2 = radiance.vertex(v[2]);
        for (int j = 0; j < m; ++j) lstar[j] = w0 * l0[j] + w1 * l1[j] + w2 * l2[j];
        const CompressedMaterial& material =
            *materials.part_material[static_cast<std::size_t>(g.part[i])];
        const Vec2 uv(g.uv[2 * i], g.uv[2 * i + 1]);
        const Vec3 e(g.view_local[4 * i], g.view_local[4 * i + 1], g.view_local[4 * i + 2]);
        image.at(x, y) = material.shade(uv, e, lstar, options.filter);
      }
    }
  });
  return image;
}

// ---- DeviceBtfShader -------------------------------------------------------------------------

struct DeviceBtfShader::Impl {
  ClContext& ctx;
  ShadingOptions options;
  int m = 0;
  std::size_t vertices = 0;
  std::size_t parts = 0;
  MaterialLightBasis basis;
  std::unique_ptr<DeviceMaterial> material;
  std::vector<std::uint64_t> part_material_bytes;  // material bytes a hit pixel of each part reads
  cl::Kernel single, view_cache, cached, view_cache_shade, misses, slot_view_samples;
  cl::Buffer indices;
  cl::Buffer code, slot_ids, slot_geom, slot_view, slot_pixel, radiance, cache, background, image;
  // The view samples of every hit slot (btf_slot_view_samples), for a material that takes them
  // precomputed (DeviceMaterial::view_sides non-empty); part_view_side its grid side per part.
  bool slot_views_used = false;
  cl::Buffer part_view_side, slot_views, slot_view_w;
  // The buffer the kernels read L* from: `radiance` (uploaded by set_radiance) or a
  // relighter's output buffer (set_radiance_buffer).
  cl::Buffer radiance_source;
  bool use_cache = false;  // options.cache_view_vectors, unless no part's material gains from it
  std::size_t pixel_capacity = 0, slot_capacity = 0, cache_capacity = 0;
  std::uint64_t static_bytes = 0;

  int width = 0, height = 0;
  std::size_t pixels = 0, slots = 0;
  std::uint64_t material_bytes_per_frame = 0;  // sum over hit pixels of part_material_bytes
  std::vector<std::int32_t> codes;
  std::vector<std::uint32_t> miss_pixels;
  std::vector<Vec3> miss_directions;
  // The hit slots as uploaded (kept between view changes: no allocation per frame).
  std::vector<cl_int2> slot_id_host;
  std::vector<cl_float4> slot_geom_host, slot_view_host;
  std::vector<cl_uint> slot_pixel_host;
  std::optional<CubemapLayout> background_layout;  // of the uploaded background, if any
  int background_pixels = 0;                       // its N (0: none; index N is black)
  bool have_gbuffer = false, have_radiance = false, cache_valid = false;
  // The image's miss pixels hold the current background (the cached pass over slots leaves
  // them as the view pass's btf_shade_misses wrote them).
  bool misses_valid = false;
  double last_cache_ms = 0.0;

  Impl(ClContext& c, const ShadingOptions& o) : ctx(c), options(o) {}

  double shade_misses() {
    set_args(misses, static_cast<cl_uint>(pixels), code, background, image);
    cl::Event ev = launch(ctx, "btf_shade_misses", misses, LaunchRange::linear(pixels, kWorkGroup));
    misses_valid = true;
    return event_ms(ctx, ev, "btf_shade_misses");
  }

  void compute_miss_codes() {
    const int black = background_pixels;
    tbb::parallel_for(std::size_t{0}, miss_pixels.size(), [&](std::size_t k) {
      const Vec3& d = miss_directions[k];
      const float dir[3] = {d.x, d.y, d.z};
      const int pixel =
          background_pixel(dir, background_layout ? &*background_layout : nullptr, black);
      codes[miss_pixels[k]] = -(1 + pixel);
    });
  }
};

DeviceBtfShader::DeviceBtfShader(ClContext& context, const Mesh& mesh,
                                 const ShadingMaterials& materials, const Cubemap* background,
                                 const ShadingOptions& options,
                                 const std::map<std::string, std::string>& material_device_options)
    : impl_(std::make_unique<Impl>(context, options)) {
  Impl& s = *impl_;
  if (materials.part_material.empty() || !materials.part_material.front())
    throw ParameterError("BTF shading: no materials given");
  s.basis = validate_materials(materials, mesh);
  s.m = s.basis.dim;
  s.vertices = mesh.positions.size();
  s.parts = materials.part_material.size();

  const std::vector<const CompressedMaterial*> parts = materials.parts();
  s.material = upload_materials(context, parts, material_device_options);
  const cl::Program program =
      build_shading_program(context, *s.material, s.m, options.filter, options.probe);
  s.single = make_kernel(program, "btf_shade_single");
  s.view_cache = make_kernel(program, "btf_view_cache");
  s.cached = make_kernel(program, "btf_shade_cached");
  s.material->set_args(s.single, kSingleMaterialArg);
  s.material->set_args(s.view_cache, kViewCacheMaterialArg);
  s.view_cache_shade = make_kernel(program, "btf_view_cache_shade");
  s.misses = make_kernel(program, "btf_shade_misses");
  s.material->set_args(s.view_cache_shade, kViewCacheShadeMaterialArg);
  if (const std::vector<int> sides = s.material->view_sides(); !sides.empty()) {
    PRT_CHECK(sides.size() == s.parts, "material {}: {} view sides for {} parts",
              s.material->label(), sides.size(), s.parts);
    s.slot_views_used = true;
    s.slot_view_samples = make_kernel(program, "btf_slot_view_samples");
    const std::vector<cl_int> side_values(sides.begin(), sides.end());
    s.part_view_side =
        upload(context, std::span<const cl_int>(side_values), "shading part view sides");
  }
  for (std::size_t p = 0; p < s.parts; ++p) {
    s.part_material_bytes.push_back(s.material->bytes_per_hit(p, options.filter));
    s.use_cache = s.use_cache || s.material->view_cache_useful(p, options.filter);
  }
  s.use_cache = s.use_cache && options.cache_view_vectors;

  s.indices = upload(context, std::span<const std::uint32_t>(mesh.indices), "shading triangles");
  s.static_bytes = mesh.indices.size() * 4 + s.material->device_bytes();
  s.radiance = make_buffer(context, s.vertices * s.m * sizeof(Rgb), CL_MEM_READ_ONLY,
                           "shading local radiance");
  set_background(background);
}

DeviceBtfShader::~DeviceBtfShader() = default;
DeviceBtfShader::DeviceBtfShader(DeviceBtfShader&&) noexcept = default;
DeviceBtfShader& DeviceBtfShader::operator=(DeviceBtfShader&&) noexcept = default;

void DeviceBtfShader::set_background(const Cubemap* background) {
  Impl& s = *impl_;
  const Cubemap* bg = s.options.background ? background : nullptr;
  const int n = bg ? bg->layout.pixel_count() : 0;
  // One black pixel past the cubemap: what misses show without a background.
  std::vector<Rgb> data(static_cast<std::size_t>(n) + 1, Rgb(0.0f));
  if (bg) std::copy(bg->radiance.begin(), bg->radiance.end(), data.begin());
  s.misses_valid = false;
  const bool layout_changed = n != s.background_pixels || !s.background();
  if (layout_changed)
    s.background = upload(s.ctx, std::span<const Rgb>(data), "shading background");
  else
    write_buffer(s.ctx, s.background, data.data(), data.size() * sizeof(Rgb), "shading background");
  if (!layout_changed) return;
  s.background_pixels = n;
  if (bg)
    s.background_layout.emplace(bg->layout);
  else
    s.background_layout.reset();
  if (s.have_gbuffer) {
    s.compute_miss_codes();
    write_buffer(s.ctx, s.code, s.codes.data(), s.pixels * sizeof(std::int32_t),
                 "shading pixel codes");
  }
}

void DeviceBtfShader::set_gbuffer(const GBuffer& g) {
  Impl& s = *impl_;
  PRT_CHECK(g.triangle.size() == g.pixel_count(), "G-buffer arrays do not match {} x {}", g.width,
            g.height);
  if (g.pixel_count() == 0) throw ParameterError("BTF shading: the G-buffer has no pixels");
  s.width = g.width;
  s.height = g.height;
  s.pixels = g.pixel_count();
  s.codes.resize(s.pixels);
  s.miss_pixels.clear();
  s.miss_directions.clear();
  // Two parallel passes over rows: count each row's hits, then (from the prefix sums) write the
  // slots, the codes and the misses in pixel order, as a serial scan would.
  const std::size_t rows = static_cast<std::size_t>(g.height),
                    w = static_cast<std::size_t>(g.width);
  std::vector<std::size_t> row_start(rows + 1, 0), row_bytes(rows, 0);
  tbb::parallel_for(std::size_t{0}, rows, [&](std::size_t y) {
    std::size_t hits = 0;
    for (std::size_t i = y * w; i < (y + 1) * w; ++i) hits += g.triangle[i] >= 0 ? 1 : 0;
    row_start[y + 1] = hits;
  });
  for (std::size_t y = 0; y < rows; ++y) row_start[y + 1] += row_start[y];
  s.slots = row_start[rows];
  s.slot_id_host.resize(s.slots);
  s.slot_geom_host.resize(s.slots);
  s.slot_view_host.resize(s.slots);
  s.slot_pixel_host.resize(s.slots);
  s.miss_pixels.resize(s.pixels - s.slots);
  s.miss_directions.resize(s.pixels - s.slots);
  const int black = s.background_pixels;
  const CubemapLayout* layout = s.background_layout ? &*s.background_layout : nullptr;
  tbb::parallel_for(std::size_t{0}, rows, [&](std::size_t y) {
    std::size_t slot = row_start[y], miss = y * w - row_start[y];
    std::uint64_t bytes = 0;
    for (std::size_t i = y * w; i < (y + 1) * w; ++i) {
      const std::int32_t tri = g.triangle[i];
      if (tri < 0) {
        s.miss_pixels[miss] = static_cast<std::uint32_t>(i);
        s.miss_directions[miss] =
            Vec3(g.direction[4 * i], g.direction[4 * i + 1], g.direction[4 * i + 2]);
        s.codes[i] = -(1 + background_pixel(&g.direction[4 * i], layout, black));
        ++miss;
        continue;
      }
      const std::int32_t part = g.part[i];
      PRT_CHECK(part >= 0 && static_cast<std::size_t>(part) < s.parts,
                "G-buffer pixel {} has part {}, {} BTFs given", i, part, s.parts);
      s.codes[i] = static_cast<std::int32_t>(slot);
      s.slot_id_host[slot] = cl_int2{{tri, part}};
      s.slot_geom_host[slot] =
          cl_float4{{g.bary[2 * i], g.bary[2 * i + 1], g.uv[2 * i], g.uv[2 * i + 1]}};
      s.slot_pixel_host[slot] = static_cast<cl_uint>(i);
      s.slot_view_host[slot] =
          cl_float4{{g.view_local[4 * i], g.view_local[4 * i + 1], g.view_local[4 * i + 2], 0.0f}};
      bytes += s.part_material_bytes[static_cast<std::size_t>(part)];
      ++slot;
    }
    row_bytes[y] = bytes;
  });
  s.material_bytes_per_frame = 0;
  for (const std::uint64_t b : row_bytes) s.material_bytes_per_frame += b;
  const auto& ids = s.slot_id_host;
  const auto& geom = s.slot_geom_host;
  const auto& view = s.slot_view_host;

  if (s.pixels > s.pixel_capacity) {
    s.code = make_buffer(s.ctx, s.pixels * sizeof(std::int32_t), CL_MEM_READ_ONLY,
                         "shading pixel codes");
    s.image = make_buffer(s.ctx, s.pixels * sizeof(Rgb), CL_MEM_WRITE_ONLY, "shaded image");
    s.pixel_capacity = s.pixels;
  }
  // Slot and cache buffers grow with 50 % headroom: the hit count changes with every view,
  // and a fresh buffer costs an allocation plus page faults on its first use.
  const std::size_t grown = s.slots + s.slots / 2 + 1;
  if (s.slots > s.slot_capacity || s.slot_capacity == 0) {
    const std::size_t n = grown;
    s.slot_ids = make_buffer(s.ctx, n * sizeof(cl_int2), CL_MEM_READ_ONLY, "shading slots");
    s.slot_geom = make_buffer(s.ctx, n * sizeof(cl_float4), CL_MEM_READ_ONLY, "shading slots");
    s.slot_view = make_buffer(s.ctx, n * sizeof(cl_float4), CL_MEM_READ_ONLY, "shading slots");
    s.slot_pixel = make_buffer(s.ctx, n * sizeof(cl_uint), CL_MEM_READ_ONLY, "shading slots");
    s.slot_views = make_buffer(s.ctx, n * sizeof(cl_int4), CL_MEM_READ_WRITE, "slot view samples");
    s.slot_view_w =
        make_buffer(s.ctx, n * sizeof(cl_float4), CL_MEM_READ_WRITE, "slot view samples");
    s.slot_capacity = n;
  }
  write_buffer(s.ctx, s.code, s.codes.data(), s.pixels * sizeof(std::int32_t),
               "shading pixel codes");
  if (s.slots > 0) {
    write_buffer(s.ctx, s.slot_ids, ids.data(), s.slots * sizeof(cl_int2), "shading slots");
    write_buffer(s.ctx, s.slot_geom, geom.data(), s.slots * sizeof(cl_float4), "shading slots");
    write_buffer(s.ctx, s.slot_view, view.data(), s.slots * sizeof(cl_float4), "shading slots");
    write_buffer(s.ctx, s.slot_pixel, s.slot_pixel_host.data(), s.slots * sizeof(cl_uint),
                 "shading slots");
  }
  if (s.use_cache && s.slots > s.cache_capacity) {
    s.cache = cl::Buffer();  // release the old one before allocating the larger one
    s.cache = make_buffer(s.ctx, grown * s.m * sizeof(Rgb), CL_MEM_READ_WRITE,
                          "view-interpolated BTF cache");
    s.cache_capacity = grown;
  }
  s.have_gbuffer = true;
  s.cache_valid = false;
  s.misses_valid = false;
}

void DeviceBtfShader::set_radiance(const LocalRadiance& radiance) {
  Impl& s = *impl_;
  check_light_basis(s.basis, radiance, s.vertices, "BTF shading");
  write_buffer(s.ctx, s.radiance, radiance.values.data(), radiance.values.size() * sizeof(Rgb),
               "shading local radiance");
  s.radiance_source = s.radiance;
  s.have_radiance = true;
}

void DeviceBtfShader::set_radiance_buffer(const cl::Buffer& radiance) {
  Impl& s = *impl_;
  const std::size_t need = s.vertices * static_cast<std::size_t>(s.m) * sizeof(Rgb);
  const auto size = radiance.getInfo<CL_MEM_SIZE>();
  if (size < need)
    throw ParameterError(fmt::format(
        "BTF shading: the local radiance buffer holds {} bytes; {} vertices x M = {} need {}", size,
        s.vertices, s.m, need));
  s.radiance_source = radiance;
  s.have_radiance = true;
}

double DeviceBtfShader::shade() {
  Impl& s = *impl_;
  if (!s.have_gbuffer || !s.have_radiance)
    throw ParameterError("BTF shading: set_gbuffer and set_radiance must precede shade()");
  s.last_cache_ms = 0.0;
  if (s.pixels == 0) return 0.0;  // OpenCL forbids an empty launch
  const auto pixels = static_cast<cl_uint>(s.pixels);
  if (!s.use_cache) {
    set_args(s.single, pixels, s.code, s.slot_ids, s.slot_geom, s.slot_view, s.indices,
             s.radiance_source, s.background, s.image);
    cl::Event ev =
        launch(s.ctx, "btf_shade_single", s.single, LaunchRange::linear(s.pixels, kWorkGroup));
    return event_ms(s.ctx, ev, "btf_shade_single");
  }
  if (!s.cache_valid && s.slots > 0) {
    // A new G-buffer: build the cache and shade the hits in one pass, then the misses.
    double views_ms = 0.0;
    if (s.slot_views_used) {
      set_args(s.slot_view_samples, static_cast<cl_uint>(s.slots), s.slot_ids, s.slot_view,
               s.part_view_side, s.slot_views, s.slot_view_w);
      cl::Event ev = launch(s.ctx, "btf_slot_view_samples", s.slot_view_samples,
                            LaunchRange::linear((s.slots + 15) / 16, kWorkGroup));
      views_ms = event_ms(s.ctx, ev, "btf_slot_view_samples");
    }
    set_args(s.view_cache_shade, static_cast<cl_uint>(s.slots), s.slot_ids, s.slot_geom,
             s.slot_view, s.slot_pixel, s.indices, s.radiance_source, s.image, s.cache,
             s.slot_views, s.slot_view_w);
    cl::Event ev = launch(s.ctx, "btf_view_cache_shade", s.view_cache_shade,
                          LaunchRange::linear(s.slots, kWorkGroup));
    s.last_cache_ms = views_ms + event_ms(s.ctx, ev, "btf_view_cache_shade");
    s.cache_valid = true;
    return s.last_cache_ms + s.shade_misses();
  }
  s.cache_valid = true;
  // A light change: only the hits change; the misses are written once per G-buffer and
  // background.
  double ms = s.misses_valid ? 0.0 : s.shade_misses();
  if (s.slots > 0) {
    set_args(s.cached, static_cast<cl_uint>(s.slots), s.slot_ids, s.slot_geom, s.slot_pixel,
             s.indices, s.radiance_source, s.cache, s.image);
    cl::Event ev =
        launch(s.ctx, "btf_shade_cached", s.cached, LaunchRange::linear(s.slots, kWorkGroup));
    ms += event_ms(s.ctx, ev, "btf_shade_cached");
  }
  return ms;
}

bool DeviceBtfShader::uses_view_cache() const {
  return impl_->use_cache;
}

double DeviceBtfShader::last_view_cache_ms() const {
  return impl_->last_cache_ms;
}

RgbImage DeviceBtfShader::read_image() const {
  Impl& s = *impl_;
  RgbImage image(s.width, s.height);
  download(s.ctx, s.image, std::span<Rgb>(image.pixels), "shaded image");
  return image;
}

DeviceBtfShader::PassBytes DeviceBtfShader::bytes_per_pass() const {
  const Impl& s = *impl_;
  const std::uint64_t vector = static_cast<std::uint64_t>(s.m) * sizeof(Rgb);
  const std::uint64_t lstar = 3 * vector * s.slots;
  PassBytes b;
  b.single_pass = s.material_bytes_per_frame + lstar;
  b.view_cache = s.material_bytes_per_frame + s.slots * vector;
  b.cached_shade = s.slots * vector + lstar;
  return b;
}

std::uint64_t DeviceBtfShader::bytes_read_per_frame() const {
  return bytes_per_pass().single_pass;
}

std::size_t DeviceBtfShader::hit_pixels() const {
  return impl_->slots;
}

std::uint64_t DeviceBtfShader::device_bytes() const {
  const Impl& s = *impl_;
  return s.static_bytes + s.vertices * s.m * sizeof(Rgb) + s.pixel_capacity * (4 + sizeof(Rgb)) +
         s.slot_capacity * (sizeof(cl_int2) + 2 * sizeof(cl_float4)) +
         s.cache_capacity * s.m * sizeof(Rgb) + (s.background_pixels + 1) * sizeof(Rgb);
}

}  // namespace prt
