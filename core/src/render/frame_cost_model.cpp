#include "prtlab/render/frame_cost_model.h"

#include <fmt/format.h>

#include <algorithm>

#include "prtlab/render/btf_shading.h"

namespace prt {
namespace {

// Per hit pixel and value of the light basis (per channel, three channels): L* interpolated from
// three vertices (3 multiplies, 2 adds), then its product with the material's value, summed.
constexpr double kInterpolationFlops = 5.0;
constexpr double kDotFlops = 2.0;
constexpr double kChannels = 3.0;
constexpr double kFloat = 4.0;

std::string ms_or_dash(double ms) {
  return ms > 0 ? fmt::format("{:.2f}", ms) : std::string("—");
}

}  // namespace

FrameCounts FrameCounts::of(const FrameRenderer& r, double transfer_bytes, double transfer_flops,
                            double material_flops_per_pixel, double light_values) {
  FrameCounts c;
  c.pixels = static_cast<double>(r.gbuffer().pixel_count());
  c.hits = static_cast<double>(r.gbuffer().hit_count());
  c.vertices = static_cast<double>(r.mesh().positions.size());
  c.visible_share = r.culls() && c.vertices > 0
                        ? static_cast<double>(r.visible_vertices().size()) / c.vertices
                        : 1.0;
  c.light_values = light_values;
  c.transfer_bytes = transfer_bytes;
  c.transfer_flops = transfer_flops;
  c.material_flops_per_pixel = material_flops_per_pixel;
  if (const DeviceBtfShader* shader = r.device_shader()) {
    c.device_shading = true;
    const auto b = shader->bytes_per_pass();
    c.view_cache_bytes = static_cast<double>(b.view_cache);
    c.cached_shade_bytes = static_cast<double>(b.cached_shade);
  }
  return c;
}

const std::vector<DeviceProfile>& model_devices() {
  static const std::vector<DeviceProfile> d = {
      {"GTX 280 (the paper's, 2008)", 141.7, 933.0, 6.0},
      {"H200 (SXM)", 4800.0, 67000.0, 50.0},
  };
  return d;
}

double model_ms(const StageCost& c, const DeviceProfile& d) {
  if (c.upload) return c.bytes / (d.link_gbps * 1e6);
  return std::max(c.bytes / (d.gbps * 1e6), c.flops / (d.gflops * 1e6));
}

FrameStageCosts frame_stage_costs(const FrameCounts& n, const FrameStageTimes& view,
                                  const FrameStageTimes& light) {
  FrameStageCosts out;
  const double m = n.light_values;
  // L*'s reads and the shading of one hit: 3 vertices' values, interpolated, dotted.
  const double lstar_bytes = 3.0 * m * kChannels * kFloat;
  const double shade_flops = m * kChannels * (kInterpolationFlops + kDotFlops);
  // G-buffer: the fields shading reads (triangle, part, barycentrics, UV, view: 40 bytes a hit)
  // plus the miss code of every pixel, written once.
  out.view.push_back({"G-buffer", n.hits * 40.0 + n.pixels * 4.0, 0.0, false, view.gbuffer_ms});
  out.view.push_back(
      {"G-buffer upload", n.hits * 44.0 + n.pixels * 4.0, 0.0, true, view.gbuffer_upload_ms});
  if (n.device_shading) {
    // The view cache pass builds every hit's vector and shades the hit in the same pass.
    out.view.push_back({"view cache + shade hits",
                        n.view_cache_bytes + n.hits * (lstar_bytes + 12.0),
                        n.hits * (kChannels * n.material_flops_per_pixel + shade_flops), false,
                        view.view_cache_kernel_ms});
    out.view.push_back({"misses (background)", (n.pixels - n.hits) * 16.0 + n.pixels * 4.0, 0.0,
                        false, view.shade_kernel_ms - view.view_cache_kernel_ms});
  }
  // The relight reads its stored state once (the share of the visible vertices when culled),
  // the light vector, and writes L*.
  out.light.push_back(
      {"relight",
       n.transfer_bytes * n.visible_share + n.vertices * n.visible_share * m * kChannels * kFloat,
       n.transfer_flops * n.visible_share, false, light.relight_kernel_ms});
  if (n.device_shading) {
    // cached_shade counts b(u, e) and the 3 vertices' L* of every hit.
    out.light.push_back({"cached shade", n.cached_shade_bytes + n.pixels * 16.0,
                         n.hits * shade_flops, false, light.shade_kernel_ms});
  }
  return out;
}

std::string cost_model_markdown(const FrameStageCosts& costs) {
  const auto& devices = model_devices();
  std::string md = "\n## Cost model\n\n";
  md +=
      "Bytes each stage moves and FLOPs it does, counted from this frame loop and the kernels "
      "(docs/rendering.md \"Cost model\"; a hit's L* interpolated from its three vertices, then "
      "dotted with the material's vector), and the time they imply on a device: max(bytes / "
      "bandwidth, FLOPs / peak) for device stages, bytes / host link for uploads, with nominal "
      "peak figures. The G-buffer is rasterised on the host here; on a GPU it would be "
      "rasterised there, modelled as writing its fields once. `measured` is this run's median "
      "(device kernel time where there is one); `GB/s here` the traffic it achieved.\n\n";
  md += "| change | stage | MB | MFLOPs | measured ms | GB/s here |";
  for (const auto& d : devices) md += fmt::format(" model ms, {} |", d.name);
  md += "\n|---|---|---:|---:|---:|---:|";
  for (std::size_t i = 0; i < devices.size(); ++i) md += "---:|";
  md += "\n";
  const auto rows = [&](const char* change, const std::vector<StageCost>& stages) {
    std::vector<double> sum(devices.size(), 0.0);
    for (const StageCost& c : stages) {
      md += fmt::format("| {} | {} | {:.2f} | {:.2f} | {} | {} |", change, c.stage, c.bytes / 1e6,
                        c.flops / 1e6, ms_or_dash(c.measured_ms),
                        c.measured_ms > 0 ? fmt::format("{:.1f}", c.bytes / (c.measured_ms * 1e6))
                                          : std::string("—"));
      for (std::size_t i = 0; i < devices.size(); ++i) {
        const double t = model_ms(c, devices[i]);
        sum[i] += t;
        md += fmt::format(" {:.3f} |", t);
      }
      md += "\n";
    }
    return sum;
  };
  const std::vector<double> view = rows("view", costs.view);
  const std::vector<double> light = rows("light", costs.light);
  md += "| **view** | **frame (model fps)** | | | | |";
  for (const double t : view) md += fmt::format(" {:.3f} ({:.0f}) |", t, t > 0 ? 1e3 / t : 0.0);
  md += "\n| **light** | **frame (model fps)** | | | | |";
  for (const double t : light) md += fmt::format(" {:.3f} ({:.0f}) |", t, t > 0 ? 1e3 / t : 0.0);
  md +=
      "\n\nThe model is a lower bound: it ignores launch overheads (tens of microseconds per "
      "kernel), gathers that waste cache-line bytes, and the host's share of a frame. A view "
      "change's light side (the newly visible vertices' relight) is not in it.\n";
  return md;
}

nlohmann::json cost_model_json(const FrameStageCosts& costs) {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& [change, stages] :
       {std::pair{"view", &costs.view}, std::pair{"light", &costs.light}})
    for (const StageCost& c : *stages) {
      nlohmann::json models = nlohmann::json::object();
      for (const auto& d : model_devices()) models[d.name] = model_ms(c, d);
      j.push_back({{"change", change},
                   {"stage", c.stage},
                   {"bytes", c.bytes},
                   {"flops", c.flops},
                   {"upload", c.upload},
                   {"measured_ms", c.measured_ms},
                   {"model_ms", models}});
    }
  return j;
}

}  // namespace prt
