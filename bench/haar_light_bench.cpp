// Ng 2003's own method on backend `haar`: the light, not T, approximated non-linearly at run
// time (compressors/haar/haar_light.h). For every scene, per-row budget k, environment, light
// weight and light term count N, one compressed archive (the stage cache's, never recompressed
// for N) is relit with the light's N best Haar coefficients and measured against the exact
// pixel-basis product T L:
//
//   light_rel_l2        ||W L~ - W L|| / ||W L|| (= the pixel-basis error, by Parseval)
//   lstar_rel_l2        ||T~ L~ - T L|| / ||T L||, every row and channel, vs the exact CSR product
//   lstar_vs_all_rel_l2 ||T~ L~ - T~ L|| / ||T~ L||: the light's share of the error alone
//   image_rel_l2, image_psnr_db   the frame loop's image (the experiments' BTFs and camera) vs
//                       the exact backend's image
//   project_ms          HaarTransfer::project_light with the approximation (C++: the transform,
//                       the ranking, the dense light)
//   cpp_rows_ms         the row product relight() (k terms a row, whatever N)
//   cpp_columns_ms      Ng's column product (haar_columns.h): only the kept columns' terms
//   opencl_ms           the device's kernel time for the same light (the row kernel; the host's
//                       projection excluded)
//   opencl_columns_ms   the same with device option opencl_order=columns (Ng's order on the device)
//   touched_terms       stored terms the column product reads
//
// The harness (`prtlab experiment`) varies compression parameters only, so this binary runs on
// its scene bench (experiments/scene_bench.h) and writes the points itself:
//
//   POCL_MAX_PTHREAD_COUNT=2 POCL_CPU_MAX_CU_COUNT=2 build/release/bench/haar_light_bench
//     --out results/haar-light [--scenes bunny,armor] [--k 12,64,256]
//     [--environments courtyard,sunset,sun:3e4] [--repeats 7] [--width 192 --height 144]
//
// It writes points.csv, provenance.json and summary.md into --out (atomically).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "experiment_spec.h"
#include "haar/haar.h"
#include "haar/haar_columns.h"
#include "haar/haar_light.h"
#include "provenance.h"
#include "prtlab/base/error.h"
#include "prtlab/compress/compression_stage.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/opencl/cl_context.h"
#include "prtlab/render/frame_renderer.h"
#include "prtlab/render/image_error.h"
#include "prtlab/storage/atomic_file.h"
#include "prtlab/transfer/exact_relight.h"
#include "scene_bench.h"
#include "scene_variants.h"

namespace {

using prt::Rgb;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;
namespace hx = prt::haar;
namespace ex = prt::experiments;

// The HaarTransfer with its project_light replaced by the run-time approximation, so that the
// frame loop (which projects the environment itself) renders with the truncated light. The
// approximation is set between frames; everything else is the wrapped transfer's.
class ApproximatedLight final : public prt::CompressedTransfer {
 public:
  explicit ApproximatedLight(std::shared_ptr<const hx::HaarTransfer> inner)
      : inner_(std::move(inner)) {}
  void set(const hx::LightApproximation& a) { approximation_ = a; }

  std::string backend() const override { return inner_->backend(); }
  prt::StorageReport storage() const override { return inner_->storage(); }
  double flops_per_relight() const override { return inner_->flops_per_relight(); }
  double declared_error_bound() const override { return inner_->declared_error_bound(); }
  prt::LightCoeffs project_light(const prt::Cubemap& radiance) const override {
    return inner_->project_light(radiance, approximation_);
  }
  void relight(const prt::LightCoeffs& light, prt::LocalRadiance& out) const override {
    inner_->relight(light, out);
  }
  bool supports_vertex_subset() const override { return inner_->supports_vertex_subset(); }
  void relight_vertices(const prt::LightCoeffs& light, std::span<const std::uint32_t> vertices,
                        prt::LocalRadiance& out) const override {
    inner_->relight_vertices(light, vertices, out);
  }
  std::unique_ptr<prt::DeviceRelighter> upload(prt::ClContext& context,
                                               const prt::ParamSet& options) const override {
    return inner_->upload(context, options);
  }
  void save(prt::ArchiveWriter& archive) const override { inner_->save(archive); }

 private:
  std::shared_ptr<const hx::HaarTransfer> inner_;
  hx::LightApproximation approximation_;
};

struct Options {
  fs::path out = "results/haar-light";
  std::vector<std::string> scenes = {"bunny"};
  std::vector<int> ks = {12, 64, 256};
  std::vector<std::string> environments = {"courtyard", "sunset", "sun:3e4"};
  std::vector<std::size_t> terms = {25, 50, 100, 200, 400, 1000, 0};  // 0: all
  int repeats = 7;
  int width = 192, height = 144;
};

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

Options parse_options(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw prt::ParameterError(fmt::format("{} needs a value", a));
      return argv[++i];
    };
    const auto integer = [&](const std::string& v) {
      std::size_t used = 0;
      const long x = std::stol(v, &used);
      if (used != v.size() || x < 0)
        throw prt::ParameterError(fmt::format("{}: '{}' is not a non-negative integer", a, v));
      return x;
    };
    if (a == "--out") {
      o.out = value();
    } else if (a == "--scenes") {
      o.scenes = split(value());
    } else if (a == "--environments") {
      o.environments = split(value());
    } else if (a == "--k") {
      o.ks.clear();
      for (const auto& v : split(value())) o.ks.push_back(static_cast<int>(integer(v)));
    } else if (a == "--terms") {
      o.terms.clear();
      for (const auto& v : split(value()))
        o.terms.push_back(v == "all" ? 0 : static_cast<std::size_t>(integer(v)));
    } else if (a == "--repeats") {
      o.repeats = static_cast<int>(std::max(1L, integer(value())));
    } else if (a == "--width") {
      o.width = static_cast<int>(integer(value()));
    } else if (a == "--height") {
      o.height = static_cast<int>(integer(value()));
    } else {
      throw prt::ParameterError(fmt::format(
          "unknown option '{}' (--out, --scenes, --k, --environments, --terms, --repeats, "
          "--width, --height)",
          a));
    }
  }
  return o;
}

template <typename Fn>
double median_ms(int repeats, const Fn& fn) {
  std::vector<double> ms;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = Clock::now();
    fn();
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
  std::sort(ms.begin(), ms.end());
  return ms[ms.size() / 2];
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// ||a - b|| / ||b|| over every value and channel, in double.
double rel_l2(std::span<const Rgb> a, std::span<const Rgb> b) {
  double err = 0, norm = 0;
  for (std::size_t i = 0; i < b.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      const double d = static_cast<double>(a[i][c]) - b[i][c];
      err += d * d;
      norm += static_cast<double>(b[i][c]) * b[i][c];
    }
  return norm > 0 ? std::sqrt(err / norm) : 0.0;
}

std::string csv_number(double v) {
  return std::isfinite(v) ? fmt::format("{:.6g}", v) : "";
}

int run(const Options& o, const std::string& command_line) {
  prt::ClContext* device = prt::default_context();
  const ex::Provenance provenance = ex::collect_provenance(command_line, device);
  prt::StageCache cache;
  const fs::path derived = o.out / ".derived";

  ex::ExperimentSpec spec;
  spec.name = "haar-light";
  spec.backends = {"haar"};
  spec.width = o.width;
  spec.height = o.height;
  spec.repeats = o.repeats;
  for (const auto& e : o.environments)
    spec.environments.push_back(ex::parse_environment("--environments", e));

  const std::vector<std::string> columns = {"scene",
                                            "k",
                                            "storage_mb",
                                            "stored_terms",
                                            "environment",
                                            "weight",
                                            "light_terms",
                                            "kept_terms",
                                            "light_rel_l2",
                                            "lstar_rel_l2",
                                            "lstar_vs_all_rel_l2",
                                            "image_rel_l2",
                                            "image_psnr_db",
                                            "project_ms",
                                            "cpp_rows_ms",
                                            "cpp_columns_ms",
                                            "opencl_ms",
                                            "opencl_columns_ms",
                                            "touched_terms",
                                            "opencl_vs_cpp_max_rel"};
  std::string csv;
  for (std::size_t i = 0; i < columns.size(); ++i) {
    if (i > 0) csv += ',';
    csv += columns[i];
  }
  csv += "\n";
  nlohmann::json info = nlohmann::json::array();

  for (const std::string& scene : o.scenes) {
    const auto variants = ex::scene_variants(scene, {}, derived);
    ex::BenchOptions bo;
    bo.device = device;
    const ex::SceneBench b = ex::prepare_bench(variants.front(), spec, cache, bo);
    const prt::TransferMatrix& t = b.prepared.transfer.result.transfer;
    info.push_back(b.info);
    std::fprintf(stderr, "%s: %zu vertices, %zu rows\n", scene.c_str(), t.vertex_count(), t.rows());
    std::vector<prt::LightCoeffs> pixel_lights;
    std::vector<prt::LocalRadiance> exact;
    for (const auto& l : b.lights) {
      pixel_lights.push_back({"pixel", l.radiance.light_vector()});
      exact.push_back(prt::relight_exact(t, pixel_lights.back().values));
    }
    const auto& entry = prt::CompressorRegistry::instance().get("haar");
    for (int k : o.ks) {
      prt::CompressionResult cr =
          prt::compress_cached("haar", {{"k", std::to_string(k)}}, b.prepared.input(entry),
                               b.prepared.transfer.key, cache);
      std::shared_ptr<const hx::HaarTransfer> h(
          dynamic_cast<const hx::HaarTransfer*>(cr.compressed.release()));
      PRT_CHECK(h != nullptr, "haar_light_bench: the haar backend returned another type");
      const hx::HaarArrays& a = h->arrays();
      const hx::HaarColumns columns_layout(a);
      const double storage_mb = static_cast<double>(h->storage().total_bytes()) / 1e6;
      std::unique_ptr<prt::DeviceRelighter> relighter =
          device ? prt::upload_compressed(*h, *device) : nullptr;
      std::unique_ptr<prt::DeviceRelighter> column_relighter =
          device ? prt::upload_compressed(*h, *device, {{"opencl_order", "columns"}}) : nullptr;
      auto wrapped = std::make_shared<ApproximatedLight>(h);
      prt::FrameRenderer renderer(b.scene.mesh, b.materials, wrapped, device);
      renderer.set_camera(b.cameras.front());
      for (std::size_t l = 0; l < b.lights.size(); ++l) {
        const prt::Cubemap& env = b.lights[l].radiance;
        prt::LocalRadiance all;
        h->relight(pixel_lights[l], all);
        for (hx::LightWeight w :
             {hx::LightWeight::kSolidAngle, hx::LightWeight::kFaceArea, hx::LightWeight::kNone}) {
          for (std::size_t n : o.terms) {
            const hx::LightApproximation approx{n, w};
            prt::LightCoeffs light;
            const double project_ms =
                median_ms(o.repeats, [&] { light = h->project_light(env, approx); });
            const prt::LightCoeffs full = h->project_light(env, {0, w});
            const hx::SparseLight sparse = hx::sparse_terms(light.values);
            prt::LocalRadiance rows, cols(prt::RadianceBasis::kPixel, a.local_count, a.vertices);
            const double rows_ms = median_ms(o.repeats, [&] { h->relight(light, rows); });
            const double cols_ms =
                median_ms(o.repeats, [&] { columns_layout.relight(sparse, cols.values); });
            PRT_CHECK(rel_l2(cols.values, rows.values) < 1e-5,
                      "haar_light_bench: the column product disagrees with the rows");
            double opencl_ms = NAN, opencl_columns_ms = NAN, opencl_vs_cpp = NAN;
            if (relighter) {
              prt::LocalRadiance gpu;
              (void)relighter->relight(light, gpu);
              opencl_vs_cpp = prt::max_relative_error(gpu, rows);
              std::vector<double> ms;
              for (int r = 0; r < o.repeats; ++r) ms.push_back(relighter->relight_on_device(light));
              opencl_ms = median(ms);
              prt::LocalRadiance gpu_columns;
              (void)column_relighter->relight(light, gpu_columns);
              opencl_vs_cpp = std::max(opencl_vs_cpp, prt::max_relative_error(gpu_columns, rows));
              ms.clear();
              for (int r = 0; r < o.repeats; ++r)
                ms.push_back(column_relighter->relight_on_device(light));
              opencl_columns_ms = median(ms);
            }
            wrapped->set(approx);
            renderer.set_environment(env);
            (void)renderer.render();
            const prt::ImageError ie =
                prt::image_error(renderer.image(), b.exact_images[l], b.masks.front());
            const std::vector<std::string> row = {
                scene,
                std::to_string(k),
                csv_number(storage_mb),
                std::to_string(a.terms()),
                b.lights[l].name,
                std::string(hx::to_string(w)),
                n == 0 ? "all" : std::to_string(n),
                std::to_string(sparse.indices.size()),
                csv_number(rel_l2(light.values, full.values)),
                csv_number(rel_l2(rows.values, exact[l].values)),
                csv_number(rel_l2(rows.values, all.values)),
                csv_number(ie.relative_l2),
                csv_number(ie.psnr_db),
                csv_number(project_ms),
                csv_number(rows_ms),
                csv_number(cols_ms),
                csv_number(opencl_ms),
                csv_number(opencl_columns_ms),
                std::to_string(columns_layout.touched_terms(sparse)),
                csv_number(opencl_vs_cpp)};
            for (std::size_t i = 0; i < row.size(); ++i) {
              if (i > 0) csv += ',';
              csv += row[i];
            }
            csv += "\n";
            std::fprintf(stderr,
                         "%s k=%d %s %s N=%s: L* %.4f image %.4f rows %.2f ms cols %.2f ms\n",
                         scene.c_str(), k, b.lights[l].name.c_str(),
                         std::string(hx::to_string(w)).c_str(), row[6].c_str(),
                         rel_l2(rows.values, exact[l].values), ie.relative_l2, rows_ms, cols_ms);
          }
        }
      }
    }
  }
  fs::create_directories(o.out);
  prt::write_text_atomically(o.out / "points.csv", csv);
  nlohmann::json prov = ex::to_json(provenance);
  prov["scenes"] = info;
  prov["repeats"] = o.repeats;
  prt::write_text_atomically(o.out / "provenance.json", prov.dump(2) + "\n");
  std::fprintf(stderr, "wrote %s (%s)\n", (o.out / "points.csv").c_str(),
               provenance.summary().c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string command_line;
  for (int i = 0; i < argc; ++i) {
    if (i > 0) command_line += ' ';
    command_line += argv[i];
  }
  try {
    return run(parse_options(argc, argv), command_line);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haar_light_bench: %s\n", e.what());
    return 1;
  }
}
