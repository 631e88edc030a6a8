#include "stability_suite.h"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "experiment_spec.h"
#include "provenance.h"
#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/base/named_warning.h"
#include "prtlab/base/progress.h"
#include "prtlab/btf/btf_generator.h"
#include "prtlab/btf/btf_materials.h"
#include "prtlab/compress/backend_evaluation.h"
#include "prtlab/compress/backend_input.h"
#include "prtlab/compress/compression_stage.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/material_error.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/geometry/mesh_io.h"
#include "prtlab/geometry/procedural_shapes.h"
#include "prtlab/image/image_io.h"
#include "prtlab/lighting/environment_map.h"
#include "prtlab/lighting/srbf_light.h"
#include "prtlab/render/image_error.h"
#include "prtlab/storage/atomic_file.h"
#include "prtlab/storage/data_paths.h"
#include "prtlab/storage/stage_cache.h"
#include "prtlab/transfer/exact_relight.h"
#include "prtlab/transfer/radiance_to_bins.h"
#include "prtlab/transfer/random_transfer.h"

namespace prt::experiments {
namespace fs = std::filesystem;

namespace {

constexpr const char* kKind = "stability";

// ---- the spec ---------------------------------------------------------------------------------

struct SuiteSpec {
  fs::path file;
  std::string name;
  std::string title;
  std::string variant;
  std::string scene = "tiny-sphere-plane";  ///< where every backend case runs
  std::vector<std::string> growth_scenes;   ///< float vs double of the exact relight
  std::vector<std::string> cases;
  std::vector<std::string> backends;
  std::vector<std::string> materials;
};

const std::set<std::string> kKeys = {"name",  "title",    "kind",      "scene",  "growth_scenes",
                                     "cases", "backends", "materials", "variant"};

std::vector<std::string> string_list(const fs::path& file, const toml::node& n,
                                     const std::string& key) {
  const auto* arr = n.as_array();
  if (!arr) throw InputError(file, fmt::format("'{}' must be a list of strings", key));
  std::vector<std::string> out;
  for (const auto& e : *arr) {
    const auto s = e.value<std::string>();
    if (!s) throw InputError(file, fmt::format("'{}' must hold strings", key));
    out.push_back(*s);
  }
  return out;
}

toml::table load(const fs::path& file) {
  try {
    return toml::parse_file(file.string());
  } catch (const toml::parse_error& e) {
    throw InputError(file, fmt::format("line {}: {}", e.source().begin.line, e.description()));
  }
}

std::vector<std::string> expand(const fs::path& file, const std::vector<std::string>& asked,
                                const std::vector<std::string>& known, const char* what) {
  if (asked.size() == 1 && asked.front() == "*") return known;
  for (const auto& a : asked)
    if (std::find(known.begin(), known.end(), a) == known.end())
      throw InputError(file,
                       fmt::format("unknown {} '{}' (known: {})", what, a, fmt::join(known, ", ")));
  return asked;
}

SuiteSpec parse_suite(const fs::path& file, const std::string& variant) {
  toml::table t = load(file);
  for (const auto& [k, v] : t)
    if (!kKeys.contains(std::string(k.str())))
      throw InputError(file,
                       fmt::format("line {}: unknown key '{}'", v.source().begin.line, k.str()));
  if (!variant.empty()) {
    const auto* vs = t["variant"].as_table();
    const auto* chosen = vs ? (*vs)[variant].as_table() : nullptr;
    if (!chosen) throw InputError(file, fmt::format("no variant '{}'", variant));
    for (const auto& [k, v] : *chosen) {
      if (!kKeys.contains(std::string(k.str())) || k.str() == "variant" || k.str() == "kind")
        throw InputError(file, fmt::format("[variant.{}]: unknown key '{}'", variant, k.str()));
      t.insert_or_assign(k.str(), v);
    }
  }
  SuiteSpec s;
  s.file = file;
  s.variant = variant;
  s.name = t["name"].value_or(std::string("stability"));
  s.title = t["title"].value_or(s.name);
  s.scene = t["scene"].value_or(s.scene);
  if (const auto* n = t["growth_scenes"].node())
    s.growth_scenes = string_list(file, *n, "growth_scenes");
  s.cases = stability_case_names();
  if (const auto* n = t["cases"].node())
    s.cases = expand(file, string_list(file, *n, "cases"), stability_case_names(), "case");
  s.backends = CompressorRegistry::instance().names();
  if (const auto* n = t["backends"].node())
    s.backends = expand(file, string_list(file, *n, "backends"), s.backends, "backend");
  s.materials = MaterialRegistry::instance().names();
  if (const auto* n = t["materials"].node())
    s.materials = expand(file, string_list(file, *n, "materials"), s.materials, "material");
  return s;
}

// ---- one row ----------------------------------------------------------------------------------

struct Row {
  std::string case_name;
  std::string subject;
  std::string outcome;  ///< ok, warned, refused, silent, crashed
  std::string detail;
  std::optional<double> error;
  std::map<std::string, int> warnings;
  double seconds = 0;
};

// What a case body reports: the error reached, and whether its result is suspect (non-finite,
// above a bound) so that the row is silent unless a warning or an error said so.
struct Measured {
  std::optional<double> error;
  std::string detail;
  bool suspect = false;
};

std::map<std::string, int> warnings_since(const std::map<std::string, int>& before) {
  std::map<std::string, int> out;
  for (const auto& [name, count] : named_warning_counts()) {
    const auto it = before.find(name);
    const int d = count - (it == before.end() ? 0 : it->second);
    if (d > 0) out[name] = d;
  }
  return out;
}

Row run_row(const std::string& case_name, const std::string& subject,
            const std::function<Measured()>& body) {
  Row row{case_name, subject, "ok", "", std::nullopt, {}, 0};
  const auto before = named_warning_counts();
  const auto t0 = std::chrono::steady_clock::now();
  try {
    const Measured m = body();
    row.error = m.error;
    row.detail = m.detail;
    row.warnings = warnings_since(before);
    if (m.suspect)
      row.outcome = row.warnings.empty() ? "silent" : "warned";
    else if (!row.warnings.empty())
      row.outcome = "warned";
  } catch (const NumericalError& e) {
    row.outcome = "refused";
    row.detail = std::string("NumericalError: ") + e.what();
  } catch (const InputError& e) {
    row.outcome = "refused";
    row.detail = std::string("InputError: ") + e.what();
  } catch (const ParameterError& e) {
    row.outcome = "refused";
    row.detail = std::string("ParameterError: ") + e.what();
  } catch (const Error& e) {
    row.outcome = "refused";
    row.detail = std::string("Error: ") + e.what();
  } catch (const std::exception& e) {
    row.outcome = "crashed";
    row.detail = std::string("unexpected exception: ") + e.what();
  }
  if (row.warnings.empty()) row.warnings = warnings_since(before);
  row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return row;
}

// ---- inputs -----------------------------------------------------------------------------------

SunSky sun_sky(double ratio) {
  SunSky s;
  const float r = static_cast<float>(ratio * 0.75);
  s.sun = {r, r * 0.95f, r * 0.85f};
  s.sun_radius_rad = 0.5 * 3.14159265358979323846 / 180.0;
  return s;
}

LocalRadiance exact_reference(const TransferMatrix& t, const Cubemap& light) {
  const auto d = relight_exact_double(t, light.light_vector());
  LocalRadiance out(RadianceBasis::kPixel, t.local_count(), t.vertex_count());
  for (std::size_t i = 0; i < d.size(); ++i) out.values[i] = Rgb(d[i]);
  return out;
}

// A backend's relight of `light` against the exact double product, through the evaluation's own
// check (non-finite values and declared bounds are its NumericalErrors).
Measured relight_case(const CompressedTransfer& ct, const TransferMatrix& t, const Cubemap& light,
                      const HemisphereGrid& grid, const std::string& light_name) {
  LocalRadiance out;
  ct.relight(ct.project_light(light), out);
  const LocalRadiance pixel = to_pixel_basis(out, grid);
  const LocalRadiance ref = exact_reference(t, light);
  check_within_declared_bound(ct, pixel, ref, light_name);
  const double e = relative_l2_error(pixel, ref);
  return {e, fmt::format("relative L2 {:.3e} vs the double product", e), !std::isfinite(e)};
}

// A scene file written for a case, its meshes beside it.
fs::path write_scene(const fs::path& dir, const std::string& name, const std::string& parts) {
  const fs::path p = dir / (name + ".toml");
  write_text_atomically(p, fmt::format("name = \"{}\"\nlocal_grid = 4\ncubemap_resolution = 8\n"
                                       "supersampling = 2\n{}",
                                       name, parts));
  return p;
}

// A sphere with zero-area triangles added: one repeating a vertex, one of three collinear
// vertices.
void write_degenerate_obj(const fs::path& p) {
  const Mesh sphere = make_sphere(0.5, 16, 8);
  std::ostringstream s;
  for (const Vec3& v : sphere.positions) s << "v " << v.x << ' ' << v.y << ' ' << v.z << '\n';
  const std::size_t n = sphere.positions.size();
  s << "v 0 2 0\nv 0.5 2 0\nv 1 2 0\n";
  for (std::size_t t = 0; t + 2 < sphere.indices.size(); t += 3)
    s << "f " << sphere.indices[t] + 1 << ' ' << sphere.indices[t + 1] + 1 << ' '
      << sphere.indices[t + 2] + 1 << '\n';
  s << "f 1 1 2\nf " << n + 1 << ' ' << n + 2 << ' ' << n + 3 << '\n';
  write_text_atomically(p, s.str());
}

// Identical vertex blocks: every cluster's rows span at most M directions, so a PCA of more
// vectors than that factors a covariance singular to rounding.
TransferMatrix rank_deficient_transfer() {
  const std::size_t vertices = 64;
  const int m = 4, n = 6 * 4 * 4, s = 2;
  std::vector<std::uint32_t> offsets{0}, columns;
  std::vector<std::uint8_t> counts;
  for (std::size_t v = 0; v < vertices; ++v)
    for (int j = 0; j < m; ++j) {
      for (int k = j; k < n; k += m) {
        columns.push_back(static_cast<std::uint32_t>(k));
        counts.push_back(static_cast<std::uint8_t>(1 + (k / m) % (s * s)));
      }
      offsets.push_back(static_cast<std::uint32_t>(counts.size()));
    }
  return TransferMatrix::from_csr(vertices, m, n, s, std::move(offsets), columns,
                                  std::move(counts));
}

// ---- the suite --------------------------------------------------------------------------------

class Suite {
 public:
  Suite(const SuiteSpec& spec, fs::path work, bool progress)
      : spec_(spec), work_(std::move(work)), progress_(progress) {}

  std::vector<Row> run() {
    for (const auto& c : spec_.cases) {
      if (progress_) log_info("stability: case {}", c);
      const auto it = cases().find(c);
      (this->*(it->second))();
    }
    return std::move(rows_);
  }

  using Case = void (Suite::*)();
  static const std::map<std::string, Case>& cases() {
    static const std::map<std::string, Case> c = {
        {"float-vs-double", &Suite::float_vs_double},
        {"hdr-sun-1e5", &Suite::hdr_sun},
        {"radiance-near-float-max", &Suite::near_float_max},
        {"nan-inf-light", &Suite::nan_light},
        {"nan-inf-mesh", &Suite::nan_mesh},
        {"degenerate-triangles", &Suite::degenerate_triangles},
        {"zero-visibility", &Suite::zero_visibility},
        {"cpca-clusters-below-n", &Suite::cpca_small_clusters},
        {"cpca-empty-clusters", &Suite::cpca_empty_clusters},
        {"cpca-near-singular", &Suite::cpca_near_singular},
        {"srbf-ill-conditioned", &Suite::srbf_ill_conditioned},
        {"hemisphere-projection", &Suite::hemisphere_projection},
        {"btf-nan-inf", &Suite::btf_nan},
        {"btf-extreme-values", &Suite::btf_extreme},
        {"zero-reference", &Suite::zero_reference},
    };
    return c;
  }

 private:
  void add(Row r) {
    if (progress_)
      log_info("  {} / {}: {}{}", r.case_name, r.subject, r.outcome,
               r.error ? fmt::format(" ({:.3e})", *r.error) : "");
    rows_.push_back(std::move(r));
  }

  // The suite scene prepared for every backend, once.
  const PreparedScene& scene() {
    if (!scene_) {
      SceneDesc desc = parse_scene(resolve_scene(spec_.scene));
      scene_.emplace(prepare_scene_for(desc, spec_.backends, cache_, {.show_progress = false}));
    }
    return *scene_;
  }

  CompressionResult compress(const PreparedScene& s, const std::string& backend,
                             const std::map<std::string, std::string>& params = {}) {
    const auto& entry = CompressorRegistry::instance().get(backend);
    return compress_cached(backend, params, s.input(entry), s.transfer.key, cache_, CacheMode::kUse,
                           false);
  }

  // Each backend compressed once at its defaults on the suite scene; a failed compression is a
  // row of the case that asked first, and later cases skip the backend.
  const CompressedTransfer* compressed(const std::string& backend, const std::string& case_name) {
    if (auto it = compressed_.find(backend); it != compressed_.end()) return it->second.get();
    std::unique_ptr<CompressedTransfer> ct;
    const Row r = run_row(case_name, backend + " (compression)", [&] {
      ct = compress(scene(), backend).compressed;
      return Measured{};
    });
    if (!ct) add(r);
    return (compressed_[backend] = std::move(ct)).get();
  }

  void over_backends(const std::string& case_name, const Cubemap& light,
                     const std::string& light_name) {
    for (const auto& b : spec_.backends) {
      const CompressedTransfer* ct = compressed(b, case_name);
      if (!ct) continue;
      add(run_row(case_name, b, [&] {
        return relight_case(*ct, scene().transfer.result.transfer, light, scene().grid, light_name);
      }));
    }
  }

  int resolution() { return scene().desc.cubemap_resolution; }

  void float_vs_double() {
    const Cubemap light = sun_sky(10).to_cubemap(resolution());
    over_backends("float-vs-double", light, "sun-10");
    for (const auto& name : spec_.growth_scenes) {
      add(run_row("float-vs-double", "exact relight on " + name, [&] {
        const SceneDesc desc = parse_scene(resolve_scene(name));
        const std::vector<std::string> none = {"uncompressed"};
        const PreparedScene p = prepare_scene_for(desc, none, cache_, {.show_progress = progress_});
        const TransferMatrix& t = p.transfer.result.transfer;
        const Cubemap l = sun_sky(10).to_cubemap(desc.cubemap_resolution);
        const LocalRadiance f = relight_exact(t, l.light_vector());
        const double e = relative_l2_error(f, exact_reference(t, l));
        return Measured{
            e,
            fmt::format("{} vertices, nnz {:.2f} M: float accumulation vs double {:.3e} "
                        "(tolerance {:.0e})",
                        t.vertex_count(), static_cast<double>(t.nnz()) / 1e6, e,
                        kFloatRoundingTolerance),
            !(e <= kFloatRoundingTolerance)};
      }));
    }
  }

  void hdr_sun() { over_backends("hdr-sun-1e5", sun_sky(1e5).to_cubemap(resolution()), "sun-1e5"); }

  void near_float_max() {
    add(run_row("radiance-near-float-max", "environment loader", [&] {
      RgbImage img(64, 32);
      for (Rgb& p : img.pixels) p = Rgb(1.f);
      img.at(10, 8) = Rgb(3e38f);
      write_exr(img, work_ / "near-max.exr");
      const LatLongImage l = load_latlong_exr(work_ / "near-max.exr");
      return Measured{std::nullopt, "loaded", true};
    }));
    // In memory, where no loader stands in between: the relight overflows and the evaluation
    // must say so.
    Cubemap light(resolution());
    for (Rgb& p : light.radiance) p = Rgb(1e38f);
    over_backends("radiance-near-float-max", light, "uniform-1e38");
  }

  void nan_light() {
    add(run_row("nan-inf-light", "environment loader", [&] {
      RgbImage img(64, 32);
      for (Rgb& p : img.pixels) p = Rgb(1.f);
      img.at(3, 3) = Rgb(std::numeric_limits<float>::quiet_NaN());
      img.at(40, 20) = Rgb(std::numeric_limits<float>::infinity(), 1.f, 1.f);
      write_exr(img, work_ / "nan.exr");
      EnvLoadReport report;
      const LatLongImage l = load_latlong_exr(work_ / "nan.exr", &report);
      bool finite = true;
      for (const Rgb& t : l.texels) finite = finite && std::isfinite(t.x + t.y + t.z);
      return Measured{std::nullopt,
                      fmt::format("{} invalid texels set to 0", report.invalid_texels), !finite};
    }));
    Cubemap light = sun_sky(1e2).to_cubemap(resolution());
    light.radiance[light.radiance.size() / 3] = Rgb(std::numeric_limits<float>::quiet_NaN());
    light.radiance[light.radiance.size() / 2] = Rgb(std::numeric_limits<float>::infinity());
    over_backends("nan-inf-light", light, "nan-and-inf-pixels");
  }

  void nan_mesh() {
    for (const auto& [format, text] : std::vector<std::pair<std::string, std::string>>{
             {"obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n"},
             {"off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 inf 0\n3 0 1 2\n"}}) {
      add(run_row("nan-inf-mesh", "mesh loader (" + format + ")",
                  [&, format = format, text = text] {
                    const fs::path p = work_ / ("nan." + format);
                    write_text_atomically(p, text);
                    const Mesh m = load_mesh(p);
                    return Measured{std::nullopt, "loaded", true};
                  }));
    }
  }

  // A case scene prepared for every backend; a failed preparation is one row.
  void over_backends_on(const std::string& case_name, const fs::path& scene_file) {
    std::optional<PreparedScene> p;
    const Row prep = run_row(case_name, "scene preparation", [&] {
      // Recomputed every run: what the mesh pipeline reports about the case's mesh is the point.
      p.emplace(prepare_scene_for(parse_scene(scene_file), spec_.backends, cache_,
                                  {.show_progress = false, .cache = CacheMode::kRefresh}));
      const TransferMatrix& t = p->transfer.result.transfer;
      // A vertex whose M rows are all empty sees no light at all.
      const auto off = t.row_offsets();
      const auto m = static_cast<std::size_t>(t.local_count());
      std::size_t empty_rows = 0;
      for (std::size_t v = 0; v < t.vertex_count(); ++v)
        empty_rows += off[v * m] == off[(v + 1) * m];
      return Measured{std::nullopt, fmt::format("{} vertices, {} of them with no visible light",
                                                t.vertex_count(), empty_rows)};
    });
    add(prep);
    if (!p) return;
    const Cubemap light = sun_sky(1e3).to_cubemap(p->desc.cubemap_resolution);
    for (const auto& b : spec_.backends) {
      add(run_row(case_name, b, [&] {
        const auto cr = compress(*p, b);
        return relight_case(*cr.compressed, p->transfer.result.transfer, light, p->grid, "sun-1e3");
      }));
    }
  }

  void degenerate_triangles() {
    write_degenerate_obj(work_ / "degenerate.obj");
    const fs::path scene = write_scene(work_, "stability-degenerate",
                                       "[[part]]\nmesh = \"degenerate.obj\"\nbtf = \"checker\"\n"
                                       "[[part]]\nmesh = \"procedural:plane\"\nbtf = \"checker\"\n"
                                       "params = { size_x = 2.0, size_z = 2.0, n = 6 }\n"
                                       "transform = { translate = [0.0, -0.6, 0.0] }\n");
    over_backends_on("degenerate-triangles", scene);
  }

  void zero_visibility() {
    // A sphere inside a closed box: its vertices see only the box.
    const fs::path scene = write_scene(work_, "stability-enclosed",
                                       "[[part]]\nmesh = \"procedural:box\"\nbtf = \"checker\"\n"
                                       "params = { hx = 1.0, hy = 1.0, hz = 1.0, n = 4 }\n"
                                       "[[part]]\nmesh = \"procedural:sphere\"\nbtf = \"bumps\"\n"
                                       "params = { radius = 0.4, segments = 12, rings = 6 }\n");
    over_backends_on("zero-visibility", scene);
  }

  bool has_backend(const std::string& b) const {
    return std::find(spec_.backends.begin(), spec_.backends.end(), b) != spec_.backends.end();
  }

  // cpca on a synthetic T small enough to compress in milliseconds: the cases are about the
  // cluster counts relative to the rows, not about the scene.
  void cpca_case(const std::string& case_name, const std::string& subject, const TransferMatrix& t,
                 const std::map<std::string, std::string>& params) {
    if (!has_backend("cpca")) return;
    add(run_row(case_name, subject, [&] {
      const CubemapLayout cube(4);
      const HemisphereGrid grid(2);
      const auto ct = CompressorRegistry::instance()
                          .create("cpca", params)
                          ->compress({t, nullptr, cube, grid}, Progress::null());
      Measured m = relight_case(*ct, t, sun_sky(10).to_cubemap(4), grid, "sun-10");
      m.detail += fmt::format(" ({} rows)", t.rows());
      return m;
    }));
  }

  static TransferMatrix random_small() {
    return random_transfer(7, RandomTransferSpec{64, 2, 4, 2, 0.5, {}});
  }

  void cpca_small_clusters() {
    // 256 rows in 64 clusters: 4 rows per cluster, below n' = 8.
    cpca_case("cpca-clusters-below-n", "cpca 64 clusters of 256 rows, vectors = 8", random_small(),
              {{"clusters", "64"}, {"vectors", "8"}});
  }

  void cpca_empty_clusters() {
    cpca_case("cpca-empty-clusters", "cpca 257 clusters of 256 rows", random_small(),
              {{"clusters", "257"}, {"vectors", "1"}});
    // Four distinct rows: the clustering cannot give 16 clusters a row each.
    cpca_case("cpca-empty-clusters", "cpca 16 clusters of 4 distinct rows",
              rank_deficient_transfer(), {{"clusters", "16"}, {"vectors", "1"}});
  }

  void cpca_near_singular() {
    cpca_case("cpca-near-singular", "cpca vectors = 8 on rank-4 rows", rank_deficient_transfer(),
              {{"clusters", "4"}, {"vectors", "8"}});
  }

  void srbf_ill_conditioned() {
    if (!has_backend("srbf_cta")) return;
    for (const auto& params : std::vector<std::map<std::string, std::string>>{
             {{"spread", "4"}},
             {{"srbfs", "2562"}, {"clusters", "2"}, {"elbg_rounds", "1"}},
             {{"spread", "4"}, {"ridge", "0"}}}) {
      std::string label;
      for (const auto& [k, v] : params) label += (label.empty() ? "" : ", ") + k + " = " + v;
      add(run_row("srbf-ill-conditioned", "srbf_cta " + label, [&] {
        const auto cr = compress(scene(), "srbf_cta", params);
        return relight_case(*cr.compressed, scene().transfer.result.transfer,
                            sun_sky(1e3).to_cubemap(resolution()), scene().grid, "sun-1e3");
      }));
    }
  }

  void hemisphere_projection() {
    for (const auto& [backend, params] :
         std::vector<std::pair<std::string, std::map<std::string, std::string>>>{
             {"sh_biscale", {{"projection", "least_squares"}, {"order", "8"}}},
             {"cpca_sh", {{"projection", "least_squares"}}}}) {
      if (!has_backend(backend)) continue;
      std::string label = backend;
      for (const auto& [k, v] : params) label += fmt::format(" {}={}", k, v);
      add(run_row("hemisphere-projection", label, [&, backend = backend, params = params] {
        const auto cr = compress(scene(), backend, params);
        // SH backends are lossy without a declared bound: their error is reported, and a
        // non-finite one is refused by the evaluation's check.
        return relight_case(*cr.compressed, scene().transfer.result.transfer,
                            sun_sky(1e3).to_cubemap(resolution()), scene().grid, "sun-1e3");
      }));
    }
  }

  std::shared_ptr<const Btf> small_btf() {
    BtfParams bp;
    bp.resolution = 8;
    bp.view_side = 4;
    bp.light_side = 4;
    return std::make_shared<const Btf>(generate_btf(make_btf_material("bumps", 16), bp));
  }

  void btf_nan() {
    const auto clean = small_btf();
    for (const float bad :
         {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
      add(run_row("btf-nan-inf", std::isnan(bad) ? "BTF with a NaN" : "BTF with an Inf", [&] {
        std::vector<float> rgb(clean->data().begin(), clean->data().end());
        rgb[rgb.size() / 2] = bad;
        const Btf b(clean->material(), clean->resolution(), clean->view_side(), clean->light_side(),
                    std::move(rgb));
        return Measured{std::nullopt, "constructed", true};
      }));
    }
  }

  void btf_extreme() {
    const auto clean = small_btf();
    std::vector<float> rgb(clean->data().begin(), clean->data().end());
    // One texel 1e30 times brighter than the rest: squared sums in float overflow.
    const std::size_t block =
        static_cast<std::size_t>(clean->view_count()) * clean->light_count() * 3;
    for (std::size_t i = 0; i < block; ++i) rgb[i] *= 1e30f;
    const auto extreme =
        std::make_shared<const Btf>(clean->material(), clean->resolution(), clean->view_side(),
                                    clean->light_side(), std::move(rgb));
    for (const auto& name : spec_.materials) {
      add(run_row("btf-extreme-values", name, [&] {
        const auto m =
            MaterialRegistry::instance().create(name, {})->compress({extreme}, Progress::null());
        const MaterialError e = material_error(*m, *extreme);
        const bool bad = !std::isfinite(e.relative_l2) ||
                         e.relative_l2 > m->declared_error_bound() * (1 + 1e-6) + 1e-5;
        return Measured{e.relative_l2,
                        fmt::format("relative L2 {:.3e} (declared bound {:.3g})", e.relative_l2,
                                    m->declared_error_bound()),
                        bad};
      }));
    }
  }

  // Every relative error against a reference that is zero: 0 / 0 is no perfect score, so a
  // finite relative error reported without the "zero-reference" warning is a silent row. The
  // row's error is the absolute one, which stays defined.
  static Measured against_zero(double relative, double absolute, const std::string& what) {
    return {absolute,
            std::isnan(relative)
                ? fmt::format("{}: relative error undefined, absolute {:.3e}", what, absolute)
                : fmt::format("{}: relative error {:.3e} against a zero reference", what, relative),
            true};
  }

  void zero_reference() {
    const Cubemap black(resolution());
    for (const auto& b : spec_.backends) {
      const CompressedTransfer* ct = compressed(b, "zero-reference");
      if (!ct) continue;
      add(run_row("zero-reference", b, [&] {
        LocalRadiance out;
        ct->relight(ct->project_light(black), out);
        const LocalRadiance pixel = to_pixel_basis(out, scene().grid);
        const LocalRadiance ref = exact_reference(scene().transfer.result.transfer, black);
        // Also holds a lossless backend to exact zeros (a NumericalError otherwise).
        check_within_declared_bound(*ct, pixel, ref, "black");
        double abs2 = 0;
        for (const Rgb& v : pixel.values)
          abs2 += static_cast<double>(v.x) * v.x + static_cast<double>(v.y) * v.y +
                  static_cast<double>(v.z) * v.z;
        return against_zero(relative_l2_error(pixel, ref), std::sqrt(abs2),
                            "relight of a black light");
      }));
    }
    add(run_row("zero-reference", "image error against a black image", [&] {
      RgbImage image(8, 8), reference(8, 8);
      for (Rgb& p : image.pixels) p = Rgb(0.25f);
      const ImageError e = image_error(image, reference);
      return against_zero(e.relative_l2, e.rmse, "image of 0.25 against black (rmse)");
    }));
    add(run_row("zero-reference", "SRBF light fit of a black map", [&] {
      ScatteredFitOptions o;
      o.count = 4;
      o.rounds = 1;
      ScatteredFitReport report;
      const SrbfLight fit = fit_scattered_srbf(black, o, &report);
      return against_zero(report.error, 0.0, "SRBF fit");
    }));
    const auto clean = small_btf();
    const auto dark = std::make_shared<const Btf>(clean->material(), clean->resolution(),
                                                  clean->view_side(), clean->light_side(),
                                                  std::vector<float>(clean->data().size(), 0.f));
    for (const auto& name : spec_.materials) {
      add(run_row("zero-reference", name + " on a black BTF", [&] {
        const auto m =
            MaterialRegistry::instance().create(name, {})->compress({dark}, Progress::null());
        const MaterialError e = material_error(*m, *dark);
        return against_zero(e.relative_l2, e.max_abs, "material error (largest absolute)");
      }));
    }
  }

  const SuiteSpec& spec_;
  fs::path work_;
  bool progress_;
  StageCache cache_;
  std::optional<PreparedScene> scene_;
  std::map<std::string, std::unique_ptr<CompressedTransfer>> compressed_;
  std::vector<Row> rows_;
};

nlohmann::json row_json(const Row& r) {
  return {{"case", r.case_name},
          {"subject", r.subject},
          {"outcome", r.outcome},
          {"detail", r.detail},
          {"error", r.error ? nlohmann::json(*r.error) : nlohmann::json(nullptr)},
          {"warnings", r.warnings},
          {"seconds", r.seconds}};
}

std::string md_cell(std::string s) {
  std::replace(s.begin(), s.end(), '|', '/');
  std::replace(s.begin(), s.end(), '\n', ' ');
  if (s.size() > 300) s = s.substr(0, 297) + "...";
  return s;
}

std::string warnings_text(const std::map<std::string, int>& w) {
  std::string s;
  for (const auto& [name, count] : w)
    s += (s.empty() ? "" : ", ") + (count == 1 ? name : fmt::format("{} x{}", name, count));
  return s;
}

std::string csv_field(const std::string& s) {
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

}  // namespace

const std::vector<std::string>& stability_case_names() {
  static const std::vector<std::string> names = {
      "float-vs-double",    "hdr-sun-1e5",           "radiance-near-float-max",
      "nan-inf-light",      "nan-inf-mesh",          "degenerate-triangles",
      "zero-visibility",    "cpca-clusters-below-n", "cpca-empty-clusters",
      "cpca-near-singular", "srbf-ill-conditioned",  "hemisphere-projection",
      "btf-nan-inf",        "btf-extreme-values",    "zero-reference"};
  return names;
}

bool is_stability_suite(const fs::path& file) {
  return declared_kind(file) == kKind;
}

std::vector<std::string> stability_suite_variants(const fs::path& file) {
  return declared_variants(file);
}

void check_stability_suite(const fs::path& file, const std::string& variant) {
  (void)parse_suite(file, variant);
}

fs::path stability_suite_folder(const fs::path& file, const std::string& variant,
                                const fs::path& out_root) {
  return out_root / (parse_suite(file, variant).name + (variant.empty() ? "" : "-" + variant));
}

nlohmann::json run_stability_suite(const fs::path& file, const StabilityOptions& o) {
  SuiteSpec spec = parse_suite(file, o.variant);
  if (!o.cases.empty()) spec.cases = expand(file, o.cases, stability_case_names(), "case");
  const fs::path folder = o.out_root / (spec.name + (o.variant.empty() ? "" : "-" + o.variant));
  const Provenance prov = collect_provenance(o.command_line, nullptr);
  const fs::path work = folder / "inputs";
  std::error_code ec;
  fs::remove(folder / ".complete", ec);
  fs::create_directories(work);

  const auto t0 = std::chrono::steady_clock::now();
  // Cases provoke warnings by design; they are counted per row, not printed as they happen.
  const LogLevel level = log_level();
  if (level < LogLevel::kError) set_log_level(o.show_progress ? LogLevel::kInfo : LogLevel::kError);
  std::vector<Row> rows;
  {
    Suite suite(spec, work, o.show_progress);
    rows = suite.run();
  }
  set_log_level(level);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  std::map<std::string, int> by_outcome;
  for (const Row& r : rows) ++by_outcome[r.outcome];
  nlohmann::json result;
  result["experiment"] = {
      {"name", spec.name},       {"title", spec.title},       {"file", file.string()},
      {"variant", spec.variant}, {"scene", spec.scene},       {"growth_scenes", spec.growth_scenes},
      {"cases", spec.cases},     {"backends", spec.backends}, {"materials", spec.materials}};
  result["provenance"] = to_json(prov);
  result["seconds"] = seconds;
  result["outcomes"] = by_outcome;
  nlohmann::json list = nlohmann::json::array();
  for (const Row& r : rows) list.push_back(row_json(r));
  result["rows"] = list;
  write_text_atomically(folder / "result.json", result.dump(2) + "\n");

  std::string csv = "case,subject,outcome,error,warnings,seconds,detail\n";
  for (const Row& r : rows)
    csv += fmt::format("{},{},{},{},{},{:.3f},{}\n", csv_field(r.case_name), csv_field(r.subject),
                       r.outcome, r.error ? fmt::format("{:.6e}", *r.error) : "",
                       csv_field(warnings_text(r.warnings)), r.seconds, csv_field(r.detail));
  write_text_atomically(folder / "cases.csv", "# " + prov.summary() + "\n" + csv);

  std::string md = fmt::format("# {}\n\n", spec.title);
  md += "Generated by `" +
        (o.command_line.empty() ? "prtlab experiment stability" : o.command_line) +
        "` (docs/experiments.md \"Stability suite\"); do not edit by hand.\n\n";
  md += "Provenance: " + prov.summary() + ". " + fmt::format("{:.0f} s.\n\n", seconds);
  md += "Outcomes: ";
  bool first = true;
  for (const auto& [k, v] : by_outcome) {
    md += fmt::format("{}{} {}", first ? "" : ", ", v, k);
    first = false;
  }
  md +=
      ".\n\n"
      "- **ok**: finite, within the declared bound; the error reached is given.\n"
      "- **warned**: detected and reported by a named warning (`prtlab: warning: [name] ...`).\n"
      "- **refused**: stopped by a named error (InputError, ParameterError, NumericalError).\n"
      "- **silent**: a non-finite or out-of-bound result that nothing reported: a defect.\n"
      "- **crashed**: an exception that is not one of prtlab's errors: a defect.\n\n";
  md +=
      "| case | subject | outcome | error reached | warnings | what happened |\n"
      "|---|---|---|---:|---|---|\n";
  auto rank = [](const std::string& outcome) {
    return outcome == "silent" ? 0 : outcome == "crashed" ? 1 : 2;
  };
  std::vector<const Row*> order;
  for (const Row& r : rows) order.push_back(&r);
  std::stable_sort(order.begin(), order.end(),
                   [&](const Row* a, const Row* b) { return rank(a->outcome) < rank(b->outcome); });
  for (const Row* r : order)
    md += fmt::format(
        "| {} | {} | {} | {} | {} | {} |\n", r->case_name, md_cell(r->subject),
        r->outcome == "silent" || r->outcome == "crashed" ? "**" + r->outcome + "**" : r->outcome,
        r->error ? fmt::format("{:.3e}", *r->error) : "", warnings_text(r->warnings),
        md_cell(r->detail));
  write_text_atomically(folder / "README.md", md);
  write_text_atomically(folder / ".complete", "");

  result["folder"] = folder.string();
  const int defects = by_outcome["silent"] + by_outcome["crashed"];
  if (defects > 0)
    throw Error(fmt::format("stability: {} silent or crashed case(s); see {}", defects,
                            (folder / "README.md").string()));
  return result;
}

}  // namespace prt::experiments
