#include <chrono>
#include <cstdio>
#include <vector>

#include "commands.h"
#include "prtlab/btf/scene_btfs.h"
#include "prtlab/geometry/scene.h"
#include "prtlab/storage/data_paths.h"

namespace prt::cli {
namespace {

struct SceneInfoOptions {
  std::string scene;
  bool json = false;
};

void run_scene_info(const SceneInfoOptions& o) {
  const auto file = resolve_scene(o.scene);
  const auto t0 = std::chrono::steady_clock::now();
  const Scene scene = load_scene(file);
  check_scene_btf_names(scene.desc);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const Mesh& mesh = scene.mesh;
  const Aabb box = mesh.bounds();
  const SceneDesc& d = scene.desc;

  std::vector<std::size_t> part_tris(d.parts.size(), 0), part_verts(d.parts.size(), 0);
  {
    std::vector<int> vertex_part(mesh.vertex_count(), -1);
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
      const std::size_t p = mesh.triangle_part.empty() ? 0 : mesh.triangle_part[t];
      ++part_tris[p];
      for (int c = 0; c < 3; ++c) vertex_part[mesh.indices[3 * t + c]] = static_cast<int>(p);
    }
    for (int p : vertex_part)
      if (p >= 0) ++part_verts[static_cast<std::size_t>(p)];
  }
  const int m = d.local_grid * d.local_grid;
  const int n = 6 * d.cubemap_resolution * d.cubemap_resolution;

  if (o.json) {
    nlohmann::json j;
    j["scene"] = d.name;
    j["file"] = file.string();
    j["description"] = d.description;
    j["vertices"] = mesh.vertex_count();
    j["triangles"] = mesh.triangle_count();
    j["bbox_min"] = {box.lo.x, box.lo.y, box.lo.z};
    j["bbox_max"] = {box.hi.x, box.hi.y, box.hi.z};
    j["local_grid"] = d.local_grid;
    j["local_directions"] = m;
    j["cubemap_resolution"] = d.cubemap_resolution;
    j["global_directions"] = n;
    j["supersampling"] = d.supersampling;
    j["has_uvs"] = mesh.has_uvs();
    j["build_seconds"] = secs;
    auto parts = nlohmann::json::array();
    for (std::size_t i = 0; i < d.parts.size(); ++i)
      parts.push_back({{"name", d.parts[i].name},
                       {"mesh", d.parts[i].mesh},
                       {"btf", d.parts[i].btf},
                       {"vertices", part_verts[i]},
                       {"triangles", part_tris[i]}});
    j["parts"] = parts;
    print_json(std::move(j));
    return;
  }
  std::printf("scene        %s (%s)\n", d.name.c_str(), file.string().c_str());
  if (!d.description.empty()) std::printf("             %s\n", d.description.c_str());
  std::printf("vertices     %zu\ntriangles    %zu\n", mesh.vertex_count(), mesh.triangle_count());
  std::printf("bounds       [%.4g %.4g %.4g] .. [%.4g %.4g %.4g]\n", box.lo.x, box.lo.y, box.lo.z,
              box.hi.x, box.hi.y, box.hi.z);
  std::printf("local grid   S = %d (M = %d)\ncubemap      R = %d (N = %d)\nsupersample  s = %d\n",
              d.local_grid, m, d.cubemap_resolution, n, d.supersampling);
  std::printf("parts        %zu\n", d.parts.size());
  for (std::size_t i = 0; i < d.parts.size(); ++i)
    std::printf("  %-12s %-28s btf %-10s %7zu verts %7zu tris\n", d.parts[i].name.c_str(),
                d.parts[i].mesh.c_str(), d.parts[i].btf.c_str(), part_verts[i], part_tris[i]);
  std::printf("built in     %.2f s\n", secs);
}

}  // namespace

void add_scene_commands(CLI::App& app) {
  auto* scene =
      app.add_subcommand("scene", "Scene files: inspect scenes (see scenes/ and docs/scenes.md)");
  scene->require_subcommand(1);

  auto opts = std::make_shared<SceneInfoOptions>();
  auto* info = scene->add_subcommand(
      "info", "Build a scene's mesh and print vertices, triangles, parts, bounds");
  info->add_option("scene", opts->scene, "Scene name (scenes/<name>.toml) or path to a .toml file")
      ->required();
  info->add_flag("--json", opts->json, "Machine-readable output (keys documented in docs/cli.md)");
  info->callback([opts] { run_scene_info(*opts); });
}

}  // namespace prt::cli
