#pragma once
// What each stage of a frame moves and computes, and the time that implies on a device
// (docs/rendering.md "Cost model"): a device stage of bandwidth B and arithmetic rate F takes
// about max(bytes / B, FLOPs / F), an upload bytes / (host link). The counts are those of the
// kernels as written (kernels/btf_shading.cl): the L* of a hit pixel is interpolated from its
// triangle's three vertices (3 multiplies and 2 adds per value) before its dot product with the
// material's vector (a multiply and an add per value).
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "prtlab/render/frame_renderer.h"

namespace prt {

/// The counts of one frame loop the model reads (FrameCounts::of fills them from a renderer).
struct FrameCounts {
  double pixels = 0;  ///< of the image
  double hits = 0;    ///< pixels that see the mesh
  double vertices = 0;
  double visible_share = 1;   ///< of the vertices the relight reaches (culling), in (0, 1]
  double light_values = 0;    ///< m: values of the materials' light basis per vertex (per channel)
  double transfer_bytes = 0;  ///< the compressed transfer's storage
  double transfer_flops = 0;  ///< FLOPs of one relight of every vertex
  double material_flops_per_pixel = 0;  ///< per channel, the largest over the parts
  bool device_shading = false;          ///< the shading stages run (a device shader exists)
  double view_cache_bytes = 0;          ///< DeviceBtfShader::bytes_per_pass().view_cache
  double cached_shade_bytes = 0;        ///< DeviceBtfShader::bytes_per_pass().cached_shade

  /// The renderer's counts at its current camera, with the transfer's and materials' costs.
  static FrameCounts of(const FrameRenderer& renderer, double transfer_bytes, double transfer_flops,
                        double material_flops_per_pixel, double light_values);
};

struct StageCost {
  std::string stage;
  double bytes = 0;  ///< device memory traffic (or, for uploads, bytes over the host link)
  double flops = 0;
  bool upload = false;
  double measured_ms = 0;  ///< this run's median (0: not separately measured)
};

/// Nominal peak figures of a device the model prices a frame on.
struct DeviceProfile {
  std::string name;
  double gbps = 0, gflops = 0, link_gbps = 0;
};

/// The paper's GPU and the one prtlab's device machines carry (vendor data sheets).
const std::vector<DeviceProfile>& model_devices();

/// max(bytes / bandwidth, FLOPs / peak) for a device stage, bytes / link for an upload.
double model_ms(const StageCost& cost, const DeviceProfile& device);

struct FrameStageCosts {
  std::vector<StageCost> view, light;
};

/// The stages of a view change and of a light change, with the measured stage medians.
FrameStageCosts frame_stage_costs(const FrameCounts& counts, const FrameStageTimes& view,
                                  const FrameStageTimes& light);

/// The model as a Markdown section ("## Cost model") and as JSON rows.
std::string cost_model_markdown(const FrameStageCosts& costs);
nlohmann::json cost_model_json(const FrameStageCosts& costs);

}  // namespace prt
