#include "scene_variants.h"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <sstream>

#include "prtlab/base/error.h"
#include "prtlab/storage/atomic_file.h"
#include "prtlab/storage/data_paths.h"

namespace prt::experiments {
namespace fs = std::filesystem;

std::vector<SceneVariant> scene_variants(
    const std::string& scene, const std::map<std::string, std::vector<std::int64_t>>& grid,
    const fs::path& derived_dir) {
  const fs::path file = resolve_scene(scene);
  toml::table base;
  try {
    base = toml::parse_file(file.string());
  } catch (const toml::parse_error& e) {
    throw InputError(file, fmt::format("line {}: {}", e.source().begin.line, e.description()));
  }
  const std::string base_name = base["name"].value_or(fs::path(file).stem().string());
  std::vector<std::map<std::string, std::int64_t>> combos = {{}};
  for (const auto& [key, values] : grid) {
    std::vector<std::map<std::string, std::int64_t>> next;
    for (const auto& c : combos)
      for (auto v : values) {
        auto d = c;
        d[key] = v;
        next.push_back(std::move(d));
      }
    combos = std::move(next);
  }
  std::vector<SceneVariant> out;
  for (const auto& c : combos) {
    SceneVariant v;
    v.base = scene;
    v.overrides = c;
    if (c.empty()) {
      v.name = base_name;
      v.file = file;
      out.push_back(std::move(v));
      continue;
    }
    toml::table t = base;
    std::string suffix;
    for (const auto& [k, value] : c) {
      t.insert_or_assign(k, value);
      suffix += fmt::format("-{}{}", k, value);
    }
    v.name = base_name + suffix;
    t.insert_or_assign("name", v.name);
    std::ostringstream text;
    // The base scene by name, not path: the file (and every stage keyed on it) is then the
    // same in every checkout.
    text << "# Derived by prtlab experiment from scene '" << base_name << "'\n" << t << "\n";
    fs::create_directories(derived_dir);
    // Mesh names resolve against the data directory, not the scene's folder, so the derived
    // file may live anywhere.
    v.file = derived_dir / (v.name + ".toml");
    write_text_atomically(v.file, text.str());
    out.push_back(std::move(v));
  }
  return out;
}

}  // namespace prt::experiments
