#include "lossless_check.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

#include "prtlab/base/error.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/sphere/cubemap.h"
#include "prtlab/transfer/exact_relight.h"

namespace prt::experiments {
namespace {

constexpr int kMaxProbeValue = 4096;  // far below float's 2^24 integer range

void require_shape(const LocalRadiance& out, const TransferMatrix& t, const std::string& backend) {
  if (out.values.size() != t.rows())
    throw Error(fmt::format("backend '{}' relit {} values, the transfer has {} rows", backend,
                            out.values.size(), t.rows()));
}

using RelightFn = std::function<void(const LightCoeffs&, LocalRadiance&)>;

void run_probes(const CompressedTransfer& ct, const TransferMatrix& t, const RelightFn& relight,
                LosslessCheck& c, LosslessPath& path) {
  const int s2 = t.supersampling() * t.supersampling();
  const int base = s2 + 1;
  int g = 0;
  for (int w = base; w <= kMaxProbeValue; w *= base) ++g;
  g = std::max(g, 1);
  c.probe_weight_base = base;
  c.columns_per_probe = 3 * g;
  const std::size_t n = t.cols();
  const std::size_t per_probe = static_cast<std::size_t>(c.columns_per_probe);
  std::vector<Rgb> light(n);
  LocalRadiance out;
  for (std::size_t first = 0; first < n; first += per_probe) {
    std::fill(light.begin(), light.end(), Rgb(0.f));
    for (std::size_t q = 0; q < per_probe && first + q < n; ++q) {
      const auto channel = static_cast<int>(q / static_cast<std::size_t>(g));
      const auto digit = static_cast<int>(q % static_cast<std::size_t>(g));
      light[first + q][channel] = static_cast<float>(std::pow(base, digit));
    }
    const LocalRadiance exact = relight_exact(t, light);
    relight(LightCoeffs{"pixel", light}, out);
    require_shape(out, t, ct.backend());
    for (std::size_t i = 0; i < exact.values.size(); ++i)
      for (int ch = 0; ch < 3; ++ch) {
        const double e = static_cast<double>(exact.values[i][ch]) * s2;
        PRT_CHECK(e == std::round(e), "probe reference {} is not an integer count code", e);
        const double err = std::abs(static_cast<double>(out.values[i][ch]) * s2 - e);
        path.max_count_error = std::max(path.max_count_error, std::isfinite(err) ? err : HUGE_VAL);
        if (!(err < 0.5)) ++path.mismatches;
      }
    path.probe_values += 3 * exact.values.size();
    ++path.probes;
  }
}

void run_random_lights(const CompressedTransfer& ct, const TransferMatrix& t, int resolution,
                       const RelightFn& relight, const LosslessCheck& c, LosslessPath& path) {
  std::mt19937_64 rng(c.seed);
  std::uniform_real_distribution<float> uniform(0.f, 1.f);
  LocalRadiance out;
  for (int l = 0; l < c.random_lights; ++l) {
    Cubemap cube(resolution);
    for (auto& px : cube.radiance) px = Rgb(uniform(rng), uniform(rng), uniform(rng));
    relight(ct.project_light(cube), out);
    require_shape(out, t, ct.backend());
    const auto ref = relight_exact_double(t, cube.light_vector());
    double largest = 0;
    for (const auto& v : ref) largest = std::max({largest, v.x, v.y, v.z});
    const double floor = std::max(1e-6 * largest, 1e-300);
    for (std::size_t i = 0; i < ref.size(); ++i)
      for (int ch = 0; ch < 3; ++ch) {
        const double e = ref[i][ch];
        const double rel =
            std::abs(static_cast<double>(out.values[i][ch]) - e) / std::max(e, floor);
        path.random_max_rel_error =
            std::max(path.random_max_rel_error, std::isfinite(rel) ? rel : HUGE_VAL);
      }
  }
}

}  // namespace

namespace {
bool path_exact(const LosslessPath& p) {
  return p.mismatches == 0 && p.random_max_rel_error < kFloatRoundingBound;
}
void explain(const LosslessPath& p, const char* name, std::string& why) {
  auto add = [&](const std::string& s) { why += (why.empty() ? "" : "; ") + s; };
  if (p.mismatches > 0)
    add(fmt::format("{}: {} of {} probe values decode to different counts", name, p.mismatches,
                    p.probe_values));
  if (p.random_max_rel_error >= kFloatRoundingBound)
    add(fmt::format("{}: random-light error {:.3g} above float rounding", name,
                    p.random_max_rel_error));
}
}  // namespace

bool LosslessCheck::exact() const {
  return probe_applicable && path_exact(cpp) && (!opencl || path_exact(*opencl));
}

std::string LosslessCheck::verdict() const {
  if (exact())
    return opencl ? "exact reconstruction (C++ and OpenCL)" : "exact reconstruction (C++)";
  std::string why;
  if (!probe_applicable) why = "count probes not applicable (light basis is not the pixel basis)";
  explain(cpp, "C++", why);
  if (opencl) explain(*opencl, "OpenCL", why);
  return "NOT exact: " + why;
}

LosslessCheck check_lossless(const CompressedTransfer& ct, const TransferMatrix& t,
                             int cubemap_resolution, const LosslessOptions& options) {
  PRT_CHECK(static_cast<std::size_t>(6 * cubemap_resolution * cubemap_resolution) == t.cols(),
            "cubemap resolution {} does not match the transfer's {} columns", cubemap_resolution,
            t.cols());
  LosslessCheck c;
  c.random_lights = options.random_lights;
  c.seed = options.seed;
  // The basis a backend's lights live in is only visible through project_light.
  c.probe_applicable = ct.project_light(Cubemap(cubemap_resolution)).basis == "pixel";
  const RelightFn cpp = [&](const LightCoeffs& l, LocalRadiance& out) { ct.relight(l, out); };
  if (c.probe_applicable) run_probes(ct, t, cpp, c, c.cpp);
  run_random_lights(ct, t, cubemap_resolution, cpp, c, c.cpp);
  if (options.device) {
    auto device = upload_compressed(ct, *options.device);
    if (!device)
      throw Error(fmt::format("backend '{}' has no OpenCL relight to check", ct.backend()));
    c.device = options.device->info().label();
    c.opencl.emplace();
    const RelightFn gpu = [&](const LightCoeffs& l, LocalRadiance& out) {
      device->relight(l, out);
    };
    if (c.probe_applicable) run_probes(ct, t, gpu, c, *c.opencl);
    run_random_lights(ct, t, cubemap_resolution, gpu, c, *c.opencl);
  }
  return c;
}

nlohmann::json to_json(const LosslessPath& p) {
  return {{"probes", p.probes},
          {"probe_values", p.probe_values},
          {"mismatches", p.mismatches},
          {"max_count_error", p.max_count_error},
          {"random_max_rel_error", p.random_max_rel_error}};
}

nlohmann::json to_json(const LosslessCheck& c) {
  return {{"exact", c.exact()},
          {"verdict", c.verdict()},
          {"method",
           "count probes: lights with weights (s^2+1)^i on disjoint columns, outputs decoded to "
           "T's counts and compared with relight_exact; plus random non-negative lights vs the "
           "double-accumulated exact product (experiments/lossless_check.h)"},
          {"probe_applicable", c.probe_applicable},
          {"columns_per_probe", c.columns_per_probe},
          {"probe_weight_base", c.probe_weight_base},
          {"random_lights", c.random_lights},
          {"random_seed", c.seed},
          {"float_rounding_bound", kFloatRoundingBound},
          {"cpp", to_json(c.cpp)},
          {"opencl", c.opencl ? to_json(*c.opencl) : nlohmann::json(nullptr)},
          {"opencl_device", c.device}};
}

}  // namespace prt::experiments
