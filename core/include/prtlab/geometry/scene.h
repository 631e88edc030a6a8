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
//   uv_scale = 4.0           # or [su, sv]: tiling of the BTF over the part's UVs
//   uv_mapping = "auto"      # "mesh" (the file's UVs), "planar" (generated), "auto": mesh
//                            # UVs where the file has them, otherwise generated
//   target_vertices = 3286   # optional, per part
//   subdivision = "loop"     # or "linear": how resampling subdivides (when the target is above
//                            # the mesh's count); "linear" keeps flat faces and sharp edges
//   groups = ["Seat*", "Back"]  # optional: only these groups of the mesh file (names or
//   group_by = "material"    # patterns with * and ?), by "material" (default) or "object"
//   transform = { scale = [1,1,1], rotate_deg = [0,0,0], translate = [0,0,0] }
//   normalize = true         # fit into the unit box resting on y = 0 before the transform
//   [part.params]            # procedural shape parameters
//   radius = 0.5
//   [[part.instance]]        # optional copies of the part (scale, then translate), after
//   translate = [1, 0, 0]    # the part's transform; without any, the part appears once
//   scale = [1, 2, 1]
//   [[view]]                 # optional camera presets (camera.h, ViewPreset); the first is
//   name = "front"           # the default view
//   from = [0, 0.3, 1]       # framed: look along -from, distance fitted to the vertices
//   fov = 40                 # vertical field of view, degrees (default 40)
//   [[view]]
//   name = "close"
//   eye = [0.5, 0.6, 1.2]    # explicit: eye position ...
//   target = [0, 0.4, 0]     # ... looking at target (default: the bounding-box centre)
//   up = [0, 1, 0]           # default +y; fill = 0.9 (framed views: image fraction)
//
// Generated UVs (uv_mapping.h) are made after resampling (chart seams would otherwise pin
// the decimation); their seam copies count towards target_vertices: the decimation target is
// lowered until the part, seams included, has the target count (within 0.2%).
//
// Parts with `groups` cut one model into parts: the file is loaded once per scene, every
// pattern must match at least one of its groups, and no group may belong to two parts. Such
// a part is welded by position (by position and UV with uv_mapping = "mesh") and its winding
// made consistent (orient_consistently) before resampling; `normalize` then uses the whole
// file's bounding box, so the parts stay where the model has them.
//
// Unknown keys are an error that lists the valid ones (a typo is never a silent default).
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "prtlab/geometry/camera.h"
#include "prtlab/geometry/mesh.h"
#include "prtlab/geometry/mesh_io.h"
#include "prtlab/geometry/mesh_processing.h"

namespace prt {

enum class UvMapping {
  kAuto,    ///< the mesh's UVs where it has them, otherwise generated
  kMesh,    ///< the mesh's UVs (an error when it has none)
  kPlanar,  ///< generated (generate_uvs), replacing any UVs of the mesh
};

struct ScenePart {
  std::string name;
  std::string mesh;  ///< data mesh name/path, or "procedural:<shape>"
  std::string btf = "lambert";
  double uv_scale = 1.0;    ///< u scale (and v scale unless uv_scale = [su, sv])
  double uv_scale_v = 1.0;  ///< v scale; equal to uv_scale when a single number is given
  UvMapping uv_mapping = UvMapping::kAuto;
  std::optional<std::size_t> target_vertices;
  bool smooth_subdivision = true;   ///< subdivision = "loop" (true) or "linear"
  std::vector<std::string> groups;  ///< group names or patterns; empty: the whole file
  MeshGroupKey group_by = MeshGroupKey::kMaterial;
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
  std::vector<ViewPreset> views;  ///< camera presets in file order (names unique)
};

/// Parse and validate a scene file (every error names the file and the key).
SceneDesc parse_scene(const std::filesystem::path& file);

struct Scene {
  SceneDesc desc;
  Mesh mesh;  ///< all parts merged; triangle_part indexes desc.parts
};

/// Build the scene's mesh: load/generate each part, resample to its target (generating UVs
/// where needed), transform, scale UVs by uv_scale, merge, compute normals and tangents.
Scene build_scene(const SceneDesc& desc);
inline Scene load_scene(const std::filesystem::path& file) {
  return build_scene(parse_scene(file));
}

/// The view preset `name` of the scene; an empty name gives the default view: the first
/// preset, or automatic_view() when the scene has none. ParameterError naming the scene file
/// and listing its presets when there is no such name.
ViewPreset scene_view(const SceneDesc& desc, std::string_view name);
/// The camera of a view of a built scene: the preset resolved against the scene's vertices at
/// the overrides' size (default 640 x 480), then the other overrides (eye, target, up, fov)
/// applied. ParameterError on an unknown preset or an invalid camera.
Camera scene_camera(const Scene& scene, std::string_view view,
                    const CameraOverrides& overrides = {});

}  // namespace prt
