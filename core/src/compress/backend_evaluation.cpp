#include "prtlab/compress/backend_evaluation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>

#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/base/named_warning.h"
#include "prtlab/base/statistics.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/light_options.h"
#include "prtlab/lighting/environment_map.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/storage/data_paths.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/transfer/radiance_to_bins.h"

namespace prt {
namespace {

LocalRadiance exact_double(const TransferMatrix& t, const Cubemap& radiance) {
  const auto d = relight_exact_double(t, radiance.light_vector());
  LocalRadiance out(RadianceBasis::kPixel, t.local_count(), t.vertex_count());
  for (std::size_t i = 0; i < d.size(); ++i) out.values[i] = Rgb(d[i]);
  return out;
}

}  // namespace

std::vector<EvaluationLight> evaluation_lights(int resolution, int limit) {
  static const char* kWorlds[] = {"courtyard", "city",   "forest",  "interior",
                                  "night",     "studio", "sunrise", "sunset"};
  std::vector<EvaluationLight> out;
  const auto dir = data_dir() / "envmaps";
  bool have_all = true;
  for (const char* w : kWorlds)
    have_all = have_all && std::filesystem::exists(dir / (std::string(w) + ".exr"));
  const int count = limit > 0 ? std::min(limit, 8) : 8;
  if (have_all) {
    const LogLevel saved = log_level();
    set_log_level(LogLevel::kError);  // the Blender maps carry a few tiny negative texels each
    for (int i = 0; i < count; ++i)
      out.push_back({kWorlds[i],
                     resample_to_cubemap(load_latlong_exr(dir / (std::string(kWorlds[i]) + ".exr")),
                                         resolution)});
    set_log_level(saved);
    return out;
  }
  log_warn(
      "data cache has no Blender world maps; evaluating with procedural sun-and-sky lights "
      "(run scripts/setup.sh --data for the real ones)");
  for (int i = 0; i < count; ++i) {
    SunSky s;
    const double a = 0.7 + 0.8 * i;
    s.sun_dir = glm::normalize(Vec3d(std::cos(a), 0.3 + 0.08 * i, std::sin(a)));
    out.push_back({fmt::format("sunsky-{}", i), s.to_cubemap(resolution)});
  }
  return out;
}

void check_within_declared_bound(const CompressedTransfer& ct, const LocalRadiance& approx,
                                 const LocalRadiance& exact, const std::string& light) {
  if (const std::size_t bad = count_nonfinite(approx.values))
    throw NumericalError(fmt::format(
        "backend '{}': relighting with light '{}' produced {} non-finite values of {} (the "
        "compressed data or the light overflows float)",
        ct.backend(), light, bad, approx.values.size()));
  if (const std::size_t bad = count_nonfinite(exact.values))
    throw NumericalError(
        fmt::format("the exact relight with light '{}' has {} non-finite values "
                    "(beyond float's range: the light is too bright to relight in float)",
                    light, bad));
  const double bound = ct.declared_error_bound();
  const bool l1 = ct.declared_error_norm() == CompressedTransfer::ErrorNorm::kRelativeL1;
  const double measured = l1 ? relative_l1_error(approx, exact) : relative_l2_error(approx, exact);
  if (std::isnan(measured)) {
    // The exact product is zero (a black light, or a T that sees none of it): no relative
    // error exists, and a lossless backend must relight to exact zeros.
    const bool zero = std::all_of(approx.values.begin(), approx.values.end(),
                                  [](const Rgb& v) { return v == Rgb(0.f); });
    if (bound == 0 && !zero)
      throw NumericalError(fmt::format(
          "backend '{}': the exact relight with light '{}' is zero, but this lossless backend "
          "relit it to non-zero values",
          ct.backend(), light));
    return;
  }
  if (!std::isfinite(bound)) {
    // No bound to hold it to, but an approximation farther from T L than zero is a failed fit.
    if (measured > 1.0)
      log_warn_named("error-above-one",
                     "backend '{}': the {} error with light '{}' is {:.3g}, worse than "
                     "relighting to zero (a failed fit: check its parameters)",
                     ct.backend(), to_string(ct.declared_error_norm()), light, measured);
    return;
  }
  if (measured <= bound * (1 + 1e-6) + kFloatRoundingTolerance) return;
  throw NumericalError(fmt::format(
      "backend '{}': the {} error with light '{}' is {:.3e}, above the bound of {:.3e} it "
      "declares{}: the compressed data is inconsistent with the transfer it was made from (a "
      "damaged or foreign archive, or a bug in the backend)",
      ct.backend(), to_string(ct.declared_error_norm()), light, measured, bound,
      bound == 0
          ? fmt::format(" (lossless, plus {:.0e} for float rounding)", kFloatRoundingTolerance)
          : ""));
}

BackendEvaluation evaluate_backend(const CompressedTransfer& ct, const TransferMatrix& exact,
                                   const std::vector<EvaluationLight>& lights, ClContext* context,
                                   const EvaluationOptions& options) {
  BackendEvaluation ev;
  PRT_CHECK(!lights.empty(), "no evaluation lights");
  const int repeats = options.repeats;
  const HemisphereGrid grid(static_cast<int>(std::lround(std::sqrt(exact.local_count()))));
  LocalRadiance out;
  for (const auto& light : lights) {
    const LightCoeffs coeffs = project_light_with(ct, light.radiance, options.light_options);
    ct.relight(coeffs, out);
    const LocalRadiance pixel = to_pixel_basis(out, grid);
    const LocalRadiance ref = exact_double(exact, light.radiance);
    check_within_declared_bound(ct, pixel, ref, light.name);
    ev.errors.push_back(
        {light.name, relative_l2_error(pixel, ref), max_relative_error(pixel, ref)});
    const VertexError v = max_vertex_error(pixel, ref, grid);
    if (v.max_relative >= ev.max_vertex_rel) {
      ev.max_vertex_rel = v.max_relative;
      ev.worst_vertex = v.worst_vertex;
    }
  }
  // 0 relights: the caller does not want the Frobenius error (ev.frobenius.relights = 0).
  if (options.frobenius_relights > 0)
    ev.frobenius = frobenius_error(ct, exact, grid, options.frobenius_relights,
                                   options.frobenius_relights, options.seed);
  for (const auto& e : ev.errors) {
    ev.mean_rel_l2 += e.rel_l2 / static_cast<double>(ev.errors.size());
    ev.max_rel_l2 = std::max(ev.max_rel_l2, e.rel_l2);
  }

  using clock = std::chrono::steady_clock;
  const LightCoeffs coeffs = project_light_with(ct, lights.front().radiance, options.light_options);
  std::vector<double> ms, ms_proj;
  for (int i = 0; i < std::max(1, repeats); ++i) {
    auto t0 = clock::now();
    const LightCoeffs c = project_light_with(ct, lights.front().radiance, options.light_options);
    ms_proj.push_back(std::chrono::duration<double, std::milli>(clock::now() - t0).count());
    t0 = clock::now();
    ct.relight(coeffs, out);
    ms.push_back(std::chrono::duration<double, std::milli>(clock::now() - t0).count());
  }
  ev.ms_cpp = median(ms);
  ev.ms_project = median(ms_proj);

  ev.device = "none";
  if (context) {
    ev.device = context->info().label();
    auto dev = upload_compressed(ct, *context, options.device_options);
    if (dev) {
      LocalRadiance gpu;
      dev->relight(coeffs, gpu);
      ev.opencl_vs_cpp = relative_l2_error(gpu, out);
      std::vector<double> kms;
      for (int i = 0; i < std::max(1, repeats); ++i) kms.push_back(dev->relight_on_device(coeffs));
      ev.ms_opencl = median(kms);
    }
  }
  return ev;
}

}  // namespace prt
