#pragma once
// Scene files (TOML, in scenes/): geometry, parts with their BTFs, and the PRT parameters.
//
//   name = "bunny"
//   description = "..."
//   local_grid = 8          # S: M = S^2 local directions
//   cubemap_resolution = 32 # R: N = 6 R^2 global directions
//   supersampling = 2       # s: visibility rays per pixel side
//   target_vertices = 3286  # optional: whole-scene vertex count after resampling
//   [[part]]
//   name = "body"
//   mesh = "bunny00.off"     # data file, or "procedural:sphere" etc. (see scene.cpp)
//   btf = "stucco"
//   uv_scale = 4.0
//   target_vertices = 3286   # optional, per part
//   transform = { scale = [1,1,1], rotate_deg = [0,0,0], translate = [0,0,0] }
//   normalize = true         # fit into the unit box resting on y = 0 before the transform
//   [part.params]            # procedural shape parameters
//   radius = 0.5
//   [[part.instance]]        # optional copies of the part (scale, then translate), after
//   translate = [1, 0, 0]    # the part's transform; without any, the part appears once
//   scale = [1, 2, 1]
//
// Unknown keys are an error that lists the valid ones (a typo is never a silent default).
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "prtlab/mesh.h"
#include "prtlab/mesh_processing.h"

namespace prt {

struct ScenePart {
  std::string name;
  std::string mesh;  ///< data mesh name/path, or "procedural:<shape>"
  std::string btf = "lambert";
  double uv_scale = 1.0;
  std::optional<std::size_t> target_vertices;
  Transform transform;
  bool normalize = false;
  std::map<std::string, double> params;  ///< procedural shape parameters
  struct Instance {
    Vec3d scale{1.0};
    Vec3d translate{0.0};
  };
  std::vector<Instance> instances;  ///< empty: one copy, untransformed
};

struct SceneDesc {
  std::filesystem::path file;
  std::string name;
  std::string description;
  int local_grid = 8;           ///< S
  int cubemap_resolution = 32;  ///< R
  int supersampling = 2;        ///< s
  std::optional<std::size_t> target_vertices;
  std::vector<ScenePart> parts;
};

/// Parse and validate a scene file (every error names the file and the key).
SceneDesc parse_scene(const std::filesystem::path& file);

struct Scene {
  SceneDesc desc;
  Mesh mesh;  ///< all parts merged; triangle_part indexes desc.parts
};

/// Build the scene's mesh: load/generate each part, resample to its target, transform,
/// merge, compute normals and tangents.
Scene build_scene(const SceneDesc& desc);
inline Scene load_scene(const std::filesystem::path& file) {
  return build_scene(parse_scene(file));
}

}  // namespace prt
