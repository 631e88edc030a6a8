#include "result_images.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>

#include "prtlab/render/image_error.h"

namespace prt::experiments {
namespace {
namespace fs = std::filesystem;
using json = nlohmann::json;

std::string slug(std::string s) {
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') c = '_';
  return s;
}

}  // namespace

json write_scene_images(const SceneBench& bench, const std::vector<PointOutcome*>& outcomes,
                        const fs::path& folder) {
  const fs::path dir = folder / "images";
  fs::create_directories(dir);
  const std::size_t lights = bench.lights.size();
  json written = json::object();
  std::vector<double> scales(bench.exact_images.size(), 0.0);
  for (const auto* o : outcomes)
    for (std::size_t i = 0; i < o->images.size(); ++i) {
      auto e = relative_error_map(o->images[i], bench.exact_images[i], bench.masks[i / lights]);
      std::vector<double> counted;
      for (std::size_t p = 0; p < e.size(); ++p)
        if (bench.masks[i / lights][p]) counted.push_back(e[p]);
      if (counted.empty()) continue;
      const std::size_t k =
          static_cast<std::size_t>(0.99 * static_cast<double>(counted.size() - 1));
      std::nth_element(counted.begin(), counted.begin() + static_cast<std::ptrdiff_t>(k),
                       counted.end());
      scales[i] = std::max(scales[i], counted[k]);
    }
  json scale_json = json::array();
  for (std::size_t i = 0; i < bench.exact_images.size(); ++i) {
    const std::size_t v = i / lights, l = i % lights;
    const std::string stem = fmt::format("{}-{}-{}", slug(bench.variant.name),
                                         slug(bench.lights[l].name), slug(bench.view_names[v]));
    ToneMap tm;
    tm.auto_exposure = false;
    tm.exposure = bench.exposure[i];
    write_png(bench.exact_images[i], dir / (stem + "-exact.png"), tm);
    if (scales[i] <= 0) scales[i] = 1e-6;
    scale_json.push_back({{"environment", bench.lights[l].name},
                          {"view", bench.view_names[v]},
                          {"exact", "images/" + stem + "-exact.png"},
                          {"error_scale", scales[i]}});
    for (auto* o : outcomes) {
      if (o->images.empty()) continue;
      const std::string b = slug(o->record["backend"].get<std::string>());
      const std::string img = stem + "-" + b + ".png", err = stem + "-" + b + "-error.png";
      write_png(o->images[i], dir / img, tm);
      write_false_colour_png(
          error_false_colour(o->images[i], bench.exact_images[i], bench.masks[v], scales[i]),
          dir / err);
      o->record["images"].push_back({{"environment", bench.lights[l].name},
                                     {"view", bench.view_names[v]},
                                     {"image", "images/" + img},
                                     {"error_map", "images/" + err},
                                     {"error_scale", scales[i]}});
    }
  }
  return scale_json;
}

}  // namespace prt::experiments
