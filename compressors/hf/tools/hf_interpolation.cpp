// hf's factors evaluated with the two halfway interpolations of Q, from the same fitted state:
// linear (sum_a w_a Q_a) and geometric (prod_a Q_a^w_a, the exponential of the interpolated
// logarithm, which is the model hf's log fit solves for). Computed here from the material's
// decoded codebooks, independently of FactoredMaterial's evaluation, beside the error of the
// material as it ships (material_error, through FactoredMaterial::reflectance). Writes
// <out>/interpolation.csv and <out>/interpolation.json with provenance.
//
//   hf_interpolation --out results/hf-interpolation [--btfs checker,rings,weave]
//       [--resolution 32] [--view-side 8] [--light-side 8] [--lambda 0.1] [--floor 0.001]
//       [--configs float,8bit,256-8bit] [--refine 0] [--tag before]
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "prtlab/base/build_info.h"
#include "prtlab/base/error.h"
#include "prtlab/btf/btf_generator.h"
#include "prtlab/btf/halfway_parameterization.h"
#include "prtlab/compress/material_error.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/render/factored_material.h"
#include "prtlab/storage/atomic_file.h"
#include "prtlab/storage/stage_cache.h"

namespace {

using prt::Rgb;
using prt::Vec3;

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

struct Errors {
  double linear = 0, geometric = 0;
  // Share of the squared error of each model on the samples below floor x the texel channel's
  // maximum (the samples hf raises before its logarithm).
  double linear_floored_share = 0, geometric_floored_share = 0;
  double floored_fraction = 0;
  // Share of the squared error of each model on the brightest 1 % of the BTF's values (the
  // highlights).
  double linear_highlight_share = 0, geometric_highlight_share = 0;
  double linear_max_abs = 0, geometric_max_abs = 0;
};

// Both interpolations of Q at every sample of the material's own state; a Q below FLT_MIN (an
// 8-bit code 0) is read as FLT_MIN in the logarithm.
Errors both_ways(const prt::FactoredMaterial& m, const prt::Btf& btf, double floor) {
  const auto& st = m.state();
  const int texels = btf.texel_count(), nv = btf.view_count(), nl = btf.light_count();
  const int h_count = st.half_side * st.half_side;
  const std::vector<Vec3> lights = prt::light_directions_f(st.sampling.light_side);
  std::vector<Vec3> views;
  for (const Vec3& e : prt::light_directions_f(st.sampling.view_side))
    views.push_back(prt::clamp_to_hemisphere(e));
  std::vector<float> sorted(btf.data().begin(), btf.data().end());
  const auto top = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() * 99 / 100);
  std::nth_element(sorted.begin(), top, sorted.end());
  const float highlight = *top;
  struct Sum {
    double ref = 0, lin = 0, geo = 0, lin_f = 0, geo_f = 0, floored = 0, lin_max = 0, geo_max = 0,
           lin_h = 0, geo_h = 0;
  };
  std::vector<Sum> sums(static_cast<std::size_t>(texels));
  tbb::parallel_for(0, texels, [&](int t) {
    Sum s;
    const float* p = st.codebook_p.data() + static_cast<std::size_t>(st.index_p[t]) * nl * 3;
    const float* q = st.codebook_q.data() + static_cast<std::size_t>(st.index_q[t]) * h_count * 3;
    const float* r = st.codebook_r.data() + static_cast<std::size_t>(st.index_r[t]) * nv * 3;
    const float* sc = st.scale.data() + static_cast<std::size_t>(t) * 3;
    float peak[3] = {0, 0, 0};
    for (int v = 0; v < nv; ++v)
      for (int j = 0; j < nl; ++j) {
        const Rgb f = btf.value(t, v, j);
        for (int c = 0; c < 3; ++c) peak[c] = std::max(peak[c], f[c]);
      }
    for (int v = 0; v < nv; ++v)
      for (int j = 0; j < nl; ++j) {
        const prt::BtfViewSamples hs = prt::halfway_samples(st.half_side, lights[j], views[v]);
        const Rgb f = btf.value(t, v, j);
        for (int c = 0; c < 3; ++c) {
          double lin = 0, log_sum = 0;
          for (int k = 0; k < 4; ++k) {
            const double qa = q[hs.view[k] * 3 + c];
            lin += hs.weight[k] * qa;
            log_sum += hs.weight[k] * std::log(std::max(qa, static_cast<double>(FLT_MIN)));
          }
          const double base = static_cast<double>(sc[c]) * p[j * 3 + c] * r[v * 3 + c];
          const double dl = base * lin - f[c], dg = base * std::exp(log_sum) - f[c];
          s.ref += static_cast<double>(f[c]) * f[c];
          s.lin += dl * dl;
          s.geo += dg * dg;
          s.lin_max = std::max(s.lin_max, std::abs(dl));
          s.geo_max = std::max(s.geo_max, std::abs(dg));
          if (f[c] > highlight) {
            s.lin_h += dl * dl;
            s.geo_h += dg * dg;
          }
          if (f[c] < floor * peak[c]) {
            s.lin_f += dl * dl;
            s.geo_f += dg * dg;
            s.floored += 1;
          }
        }
      }
    sums[static_cast<std::size_t>(t)] = s;
  });
  Sum all;
  for (const Sum& s : sums) {
    all.ref += s.ref;
    all.lin += s.lin;
    all.geo += s.geo;
    all.lin_f += s.lin_f;
    all.geo_f += s.geo_f;
    all.floored += s.floored;
    all.lin_h += s.lin_h;
    all.geo_h += s.geo_h;
    all.lin_max = std::max(all.lin_max, s.lin_max);
    all.geo_max = std::max(all.geo_max, s.geo_max);
  }
  Errors e;
  e.linear = std::sqrt(all.lin / all.ref);
  e.geometric = std::sqrt(all.geo / all.ref);
  e.linear_floored_share = all.lin > 0 ? all.lin_f / all.lin : 0;
  e.geometric_floored_share = all.geo > 0 ? all.geo_f / all.geo : 0;
  e.floored_fraction = all.floored / (3.0 * texels * nv * nl);
  e.linear_highlight_share = all.lin > 0 ? all.lin_h / all.lin : 0;
  e.geometric_highlight_share = all.geo > 0 ? all.geo_h / all.geo : 0;
  e.linear_max_abs = all.lin_max;
  e.geometric_max_abs = all.geo_max;
  return e;
}

std::map<std::string, std::string> config_params(const std::string& config) {
  // The btf-table's hf rows (experiments/btf-table.toml).
  if (config == "float")
    return {
        {"clusters", "0"}, {"quantize", "false"}, {"refit_scale", "false"}, {"code_gamma", "1"}};
  if (config == "8bit")
    return {{"clusters", "0"}, {"quantize", "true"}, {"refit_scale", "false"}, {"code_gamma", "1"}};
  if (config == "256-8bit")
    return {
        {"clusters", "256"}, {"quantize", "true"}, {"refit_scale", "false"}, {"code_gamma", "1"}};
  if (config == "prtlab-256-8bit") return {{"clusters", "256"}, {"quantize", "true"}};
  throw prt::ParameterError(fmt::format(
      "--configs: unknown configuration '{}' (float, 8bit, 256-8bit, prtlab-256-8bit)", config));
}

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  return buf;
}

int run(int argc, char** argv) {
  std::map<std::string, std::string> opt = {{"out", ""},          {"btfs", "checker,rings,weave"},
                                            {"resolution", "32"}, {"view-side", "8"},
                                            {"light-side", "8"},  {"lambda", "0.1"},
                                            {"floor", "0.001"},   {"configs", "float"},
                                            {"tag", ""},          {"refine", "0"}};
  std::string command = "hf_interpolation";
  for (int i = 1; i < argc; ++i) {
    command += std::string(" ") + argv[i];
    const std::string a = argv[i];
    if (a.rfind("--", 0) != 0 || !opt.count(a.substr(2)) || i + 1 >= argc)
      throw prt::ParameterError(
          fmt::format("argument '{}': expected --key value with key one of "
                      "out btfs resolution view-side light-side lambda "
                      "floor configs tag refine",
                      a));
    opt[a.substr(2)] = argv[++i];
    command += std::string(" ") + argv[i];
  }
  if (opt["out"].empty()) throw prt::ParameterError("--out: the output folder is required");
  const std::filesystem::path out = opt["out"];
  std::filesystem::create_directories(out);
  const prt::BuildInfo& b = prt::build_info();
  nlohmann::json rows = nlohmann::json::array();
  std::string csv =
      "btf,config,lambda,floor,refine,shipped_rel_l2,linear_rel_l2,geometric_rel_l2,linear_max_abs,"
      "geometric_max_abs,floored_sample_fraction,linear_floored_error_share,"
      "geometric_floored_error_share,linear_highlight_error_share,"
      "geometric_highlight_error_share\n";
  prt::StageCache cache;
  for (const std::string& name : split(opt["btfs"])) {
    prt::BtfParams bp;
    bp.resolution = std::stoi(opt["resolution"]);
    bp.view_side = std::stoi(opt["view-side"]);
    bp.light_side = std::stoi(opt["light-side"]);
    auto g = prt::generate_btf_cached(name, bp, cache, prt::CacheMode::kUse, true);
    const auto btf = std::make_shared<const prt::Btf>(std::move(g.btf));
    for (const std::string& config : split(opt["configs"])) {
      auto params = config_params(config);
      params["lambda"] = opt["lambda"];
      params["floor"] = opt["floor"];
      params["refine"] = opt["refine"];
      const auto material = prt::compress_material("hf", params, btf);
      const auto* fm = dynamic_cast<const prt::FactoredMaterial*>(material.get());
      PRT_CHECK(fm != nullptr, "hf_interpolation: hf did not give a factored material");
      const double shipped = prt::material_error(*fm, *btf).relative_l2;
      const Errors e = both_ways(*fm, *btf, std::stod(opt["floor"]));
      std::fprintf(stderr, "%s %s: shipped %.6g linear %.6g geometric %.6g\n", name.c_str(),
                   config.c_str(), shipped, e.linear, e.geometric);
      rows.push_back({{"btf", name},
                      {"config", config},
                      {"params", params},
                      {"shipped_rel_l2", shipped},
                      {"linear_rel_l2", e.linear},
                      {"geometric_rel_l2", e.geometric},
                      {"linear_max_abs", e.linear_max_abs},
                      {"geometric_max_abs", e.geometric_max_abs},
                      {"floored_sample_fraction", e.floored_fraction},
                      {"linear_floored_error_share", e.linear_floored_share},
                      {"geometric_floored_error_share", e.geometric_floored_share},
                      {"linear_highlight_error_share", e.linear_highlight_share},
                      {"geometric_highlight_error_share", e.geometric_highlight_share}});
      csv += fmt::format(
          "{},{},{},{},{},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g}\n",
          name, config, opt["lambda"], opt["floor"], opt["refine"], shipped, e.linear, e.geometric,
          e.linear_max_abs, e.geometric_max_abs, e.floored_fraction, e.linear_floored_share,
          e.geometric_floored_share, e.linear_highlight_share, e.geometric_highlight_share);
    }
  }
  const std::string stem = opt["tag"].empty() ? "interpolation" : "interpolation-" + opt["tag"];
  const nlohmann::json doc = {{"provenance",
                               {{"version", b.version},
                                {"git", b.git_hash},
                                {"build_type", b.build_type},
                                {"compiler", b.compiler},
                                {"machine", prt::machine_description()},
                                {"date_utc", utc_now()},
                                {"command", command}}},
                              {"btf",
                               {{"resolution", opt["resolution"]},
                                {"view_side", opt["view-side"]},
                                {"light_side", opt["light-side"]}}},
                              {"rows", rows}};
  prt::write_text_atomically(out / (stem + ".json"), doc.dump(2) + "\n");
  prt::write_text_atomically(
      out / (stem + ".csv"),
      fmt::format("# git {} {}; {}; {}\n", b.git_hash, b.build_type, utc_now(), command) + csv);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hf_interpolation: %s\n", e.what());
    return 1;
  }
}
