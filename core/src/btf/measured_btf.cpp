#include "prtlab/btf/measured_btf.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

#if defined(__unix__) || defined(__APPLE__)
#include <unistd.h>
#endif

#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/sphere/hemisphere_grid.h"

namespace prt {

namespace {

// Below this cosine a measured light cannot be converted to the cell-mean convention: dividing
// by it would turn noise at the horizon into arbitrarily large values.
constexpr double kMinMeasuredCosine = 1e-3;

double degrees(double radians) {
  return radians * 180.0 / kPi;
}

// Btf's largest tile side (btf.cpp).
constexpr int kMaxResolution = 4096;
// measured_import_byte_limit() where the physical memory cannot be read.
constexpr std::uint64_t kFallbackByteLimit = std::uint64_t{16} << 30;

std::uint64_t mul_sat(std::uint64_t a, std::uint64_t b) {
  if (a != 0 && b > std::numeric_limits<std::uint64_t>::max() / a)
    return std::numeric_limits<std::uint64_t>::max();
  return a * b;
}

std::uint64_t add_sat(std::uint64_t a, std::uint64_t b) {
  return b > std::numeric_limits<std::uint64_t>::max() - a
             ? std::numeric_limits<std::uint64_t>::max()
             : a + b;
}

std::string gib(std::uint64_t bytes) {
  return fmt::format("{:.1f} GiB", static_cast<double>(bytes) / static_cast<double>(1ull << 30));
}

// "view 3 (theta 30.0, phi 90.0 deg)"
std::string direction_text(const char* what, int index, const Vec3d& d) {
  double phi = degrees(std::atan2(d.y, d.x));
  if (phi < 0) phi += 360.0;
  return fmt::format("{} {} (theta {:.2f}, phi {:.2f} deg)", what, index,
                     degrees(std::acos(std::clamp(d.z, -1.0, 1.0))), phi);
}

}  // namespace

LightCosine parse_light_cosine(const std::string& name) {
  if (name == "cell-mean") return LightCosine::kCellMean;
  if (name == "as-stored") return LightCosine::kAsStored;
  throw ParameterError(
      fmt::format("unknown light cosine mode '{}' (valid: cell-mean, as-stored)", name));
}

std::string light_cosine_name(LightCosine cosine) {
  return cosine == LightCosine::kCellMean ? "cell-mean" : "as-stored";
}

nlohmann::json MeasuredCoverage::to_json() const {
  return {{"measured_resolution", measured_resolution},
          {"measured_views", measured_views},
          {"measured_lights", measured_lights},
          {"views_used", views_used},
          {"lights_used", lights_used},
          {"max_view_angle_deg", max_view_angle_deg},
          {"mean_view_angle_deg", mean_view_angle_deg},
          {"max_light_angle_deg", max_light_angle_deg},
          {"mean_light_angle_deg", mean_light_angle_deg},
          {"box_factor", box_factor},
          {"negative_clamped", negative_clamped},
          {"values_checked", values_checked}};
}

Vec3d direction_from_angles(double theta, double phi) {
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

NearestDirections nearest_directions(const std::vector<Vec3d>& grid,
                                     const std::vector<Vec3d>& measured,
                                     const std::vector<bool>& usable) {
  PRT_CHECK(!measured.empty(), "no measured directions");
  PRT_CHECK(usable.empty() || usable.size() == measured.size(),
            "usable has {} entries, {} expected", usable.size(), measured.size());
  NearestDirections out;
  out.index.assign(grid.size(), -1);
  out.angle.assign(grid.size(), 0.0);
  for (std::size_t g = 0; g < grid.size(); ++g) {
    double best = -2.0;
    for (std::size_t m = 0; m < measured.size(); ++m) {
      if (!usable.empty() && !usable[m]) continue;
      const double d = glm::dot(grid[g], measured[m]);
      if (d > best) {
        best = d;
        out.index[g] = static_cast<int>(m);
      }
    }
    PRT_CHECK(out.index[g] >= 0, "no usable measured direction");
    out.angle[g] = std::acos(std::clamp(best, -1.0, 1.0));
  }
  return out;
}

double measured_value_factor(LightCosine cosine, bool cosine_in_data, double cell_mean_cosine,
                             double measured_cos) {
  if (cosine == LightCosine::kAsStored) return 1.0;
  return cosine_in_data ? cell_mean_cosine / measured_cos : cell_mean_cosine;
}

std::uint64_t measured_import_bytes(int measured_resolution, const MeasuredImportOptions& options) {
  const std::uint64_t w = static_cast<std::uint64_t>(std::max(measured_resolution, 0));
  const std::uint64_t u =
      options.resolution == 0 ? w : static_cast<std::uint64_t>(std::max(options.resolution, 0));
  const std::uint64_t views = static_cast<std::uint64_t>(std::max(options.view_side, 0)) *
                              static_cast<std::uint64_t>(std::max(options.view_side, 0));
  const std::uint64_t lights = static_cast<std::uint64_t>(std::max(options.light_side, 0)) *
                               static_cast<std::uint64_t>(std::max(options.light_side, 0));
  const std::uint64_t output =
      mul_sat(mul_sat(mul_sat(u, u), mul_sat(views, lights)), 3 * sizeof(float));
  const std::uint64_t scratch = add_sat(mul_sat(mul_sat(w, w), 3 * sizeof(float)),
                                        mul_sat(mul_sat(u, u), 3 * sizeof(double)));
  const auto threads =
      static_cast<std::uint64_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
  return add_sat(output, mul_sat(scratch, threads));
}

std::uint64_t measured_import_byte_limit() {
#if defined(__unix__) || defined(__APPLE__)
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  if (pages > 0 && page > 0)
    return mul_sat(static_cast<std::uint64_t>(pages), static_cast<std::uint64_t>(page));
#endif
  return kFallbackByteLimit;
}

void check_measured_import(const std::filesystem::path& file, int measured_resolution,
                           const MeasuredImportOptions& options) {
  if (options.view_side < 1 || options.view_side > 64)
    throw ParameterError(fmt::format("view side {} is outside 1..64", options.view_side));
  if (options.light_side < 1 || options.light_side > 64)
    throw ParameterError(fmt::format("light side {} is outside 1..64", options.light_side));
  if (!std::isfinite(options.scale) || options.scale <= 0)
    throw ParameterError(fmt::format("scale {} must be finite and > 0", options.scale));
  PRT_CHECK(measured_resolution > 0, "measured resolution {}", measured_resolution);
  const int w = measured_resolution;
  const int u = options.resolution == 0 ? w : options.resolution;
  if (u < 1 || u > w || w % u != 0) {
    std::vector<int> divisors;
    for (int d = 1; d <= w; ++d)
      if (w % d == 0) divisors.push_back(d);
    throw ParameterError(fmt::format(
        "resolution {} must divide the measured tile size {} (box filter by an integer factor); "
        "valid: {}",
        options.resolution, w, fmt::join(divisors, ", ")));
  }
  if (u > kMaxResolution)
    throw InputError(file, fmt::format("the measured tiles are {} x {} texels, more than prtlab's "
                                       "largest BTF resolution {}; box-filter them with "
                                       "--resolution (a divisor of {} up to {})",
                                       w, w, kMaxResolution, w, kMaxResolution));
  const std::uint64_t bytes = measured_import_bytes(w, options);
  const std::uint64_t limit = measured_import_byte_limit();
  if (bytes > limit)
    throw InputError(
        file, fmt::format("importing {} x {} measured texels at resolution {} onto {} x {} views "
                          "and {} x {} lights needs {} ({} bytes), more than the {} limit (the "
                          "physical memory; 16 GiB where unknown); lower --resolution, "
                          "--view-side or --light-side",
                          w, w, u, options.view_side, options.view_side, options.light_side,
                          options.light_side, gib(bytes), bytes, gib(limit)));
}

MeasuredBtf resample_measured(const MeasuredSource& source, const MeasuredImportOptions& options) {
  PRT_CHECK(source.resolution > 0 && source.tile, "measured source without tiles");
  check_measured_import(source.file, source.resolution, options);
  if (source.views.empty() || source.lights.empty())
    throw InputError(source.file, "no measured view or light directions");
  const int w = source.resolution;
  const int u = options.resolution == 0 ? w : options.resolution;
  const int factor = w / u;

  const HemisphereGrid view_grid(options.view_side), light_grid(options.light_side);
  const std::vector<double> projected = light_grid.projected_solid_angles();
  const double omega = light_grid.cell_solid_angle();

  std::vector<bool> usable_lights(source.lights.size(), true);
  const bool divide_cosine = options.cosine == LightCosine::kCellMean && source.cosine_in_data;
  if (divide_cosine) {
    bool any = false;
    for (std::size_t m = 0; m < source.lights.size(); ++m) {
      usable_lights[m] = source.lights[m].z >= kMinMeasuredCosine;
      any = any || usable_lights[m];
    }
    if (!any)
      throw InputError(source.file,
                       "every measured light lies at or below the horizon; its cosine cannot be "
                       "divided out (use the as-stored light cosine)");
  }
  const NearestDirections nv = nearest_directions(view_grid.directions(), source.views);
  const NearestDirections nl =
      nearest_directions(light_grid.directions(), source.lights, usable_lights);

  // Each measured pair is decoded once, however many grid cells take it.
  struct Pair {
    int view, light;
    std::vector<std::pair<int, int>> targets;  // (grid view, grid light)
  };
  std::vector<Pair> pairs;
  std::map<std::pair<int, int>, std::size_t> slot;
  const int gv_count = view_grid.cell_count(), gl_count = light_grid.cell_count();
  for (int gv = 0; gv < gv_count; ++gv) {
    for (int gl = 0; gl < gl_count; ++gl) {
      const std::pair<int, int> key{nv.index[gv], nl.index[gl]};
      auto [it, inserted] = slot.try_emplace(key, pairs.size());
      if (inserted) pairs.push_back({key.first, key.second, {}});
      pairs[it->second].targets.emplace_back(gv, gl);
    }
  }

  const std::size_t texels = static_cast<std::size_t>(u) * u;
  const std::size_t fine = static_cast<std::size_t>(w) * w;
  std::vector<float> rgb(texels * gv_count * gl_count * 3);
  const double inv_area = 1.0 / (static_cast<double>(factor) * factor);
  auto file_of = [&](int view, int light) {
    return source.tile_file ? source.tile_file(view, light) : source.file;
  };
  auto where = [&](const Pair& pair, std::size_t texel, int c) {
    return fmt::format("{}, {}, texel ({}, {}) channel {}",
                       direction_text("measured view", pair.view, source.views[pair.view]),
                       direction_text("light", pair.light, source.lights[pair.light]), texel % w,
                       texel / w, "RGB"[c]);
  };
  std::atomic<std::uint64_t> negative{0};
  tbb::parallel_for(std::size_t{0}, pairs.size(), [&](std::size_t p) {
    const Pair& pair = pairs[p];
    std::vector<float> tile(fine * 3);
    source.tile(pair.view, pair.light, tile);
    // Non-finite values are errors; negative ones are clamped to 0 and counted.
    std::uint64_t clamped = 0;
    for (std::size_t i = 0; i < tile.size(); ++i) {
      float& v = tile[i];
      if (!std::isfinite(v))
        throw InputError(file_of(pair.view, pair.light),
                         fmt::format("{} is {}; measured values must be finite",
                                     where(pair, i / 3, static_cast<int>(i % 3)), v));
      if (v < 0) {
        v = 0;
        ++clamped;
      }
    }
    if (clamped != 0) negative.fetch_add(clamped, std::memory_order_relaxed);
    std::vector<double> box(texels * 3, 0.0);
    for (int y = 0; y < w; ++y) {
      for (int x = 0; x < w; ++x) {
        const std::size_t t = static_cast<std::size_t>(y / factor) * u + x / factor;
        const float* src = tile.data() + (static_cast<std::size_t>(y) * w + x) * 3;
        for (int c = 0; c < 3; ++c) box[t * 3 + c] += src[c];
      }
    }
    if (factor > 1)
      for (double& v : box) v *= inv_area;
    const double measured_cos = source.lights[pair.light].z;
    for (const auto& [gv, gl] : pair.targets) {
      const double f = options.scale * measured_value_factor(options.cosine, source.cosine_in_data,
                                                             projected[gl] / omega, measured_cos);
      for (std::size_t t = 0; t < texels; ++t) {
        const std::size_t o = ((t * gv_count + gv) * gl_count + gl) * 3;
        for (int c = 0; c < 3; ++c) {
          const double b = box[t * 3 + c] * f;
          if (!(b <= std::numeric_limits<float>::max()))
            throw InputError(
                file_of(pair.view, pair.light),
                fmt::format("{} becomes {} after the light cosine and scale conversion, more "
                            "than a float holds; lower --scale",
                            where(pair, (t / u) * factor * w + (t % u) * factor, c), b));
          rgb[o + c] = static_cast<float>(b);
        }
      }
    }
  });

  MeasuredCoverage cov;
  cov.measured_resolution = w;
  cov.measured_views = static_cast<int>(source.views.size());
  cov.measured_lights = static_cast<int>(source.lights.size());
  cov.box_factor = factor;
  cov.negative_clamped = negative.load();
  cov.values_checked = static_cast<std::uint64_t>(pairs.size()) * fine * 3;
  if (cov.negative_clamped != 0)
    log_warn("{}: {} of {} measured values were negative and were clamped to 0",
             source.file.string(), cov.negative_clamped, cov.values_checked);
  auto summarise = [](const NearestDirections& n, int& used, double& max_deg, double& mean_deg) {
    std::vector<int> idx = n.index;
    std::sort(idx.begin(), idx.end());
    used = static_cast<int>(std::unique(idx.begin(), idx.end()) - idx.begin());
    double sum = 0;
    max_deg = 0;
    for (double a : n.angle) {
      max_deg = std::max(max_deg, degrees(a));
      sum += degrees(a);
    }
    mean_deg = n.angle.empty() ? 0.0 : sum / static_cast<double>(n.angle.size());
  };
  summarise(nv, cov.views_used, cov.max_view_angle_deg, cov.mean_view_angle_deg);
  summarise(nl, cov.lights_used, cov.max_light_angle_deg, cov.mean_light_angle_deg);

  nlohmann::json parameters = source.parameters;
  parameters["measured"] = cov.to_json();
  parameters["resampling"] = "nearest direction per view and per light, box-filtered texels";
  parameters["light_cosine"] = light_cosine_name(options.cosine);
  parameters["scale"] = options.scale;
  const std::string material = options.material.empty() ? source.material : options.material;
  return {Btf(material, u, options.view_side, options.light_side, std::move(rgb),
              std::move(parameters)),
          cov};
}

}  // namespace prt
