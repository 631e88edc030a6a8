#include "prtlab/geometry/scene.h"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <utility>

#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/geometry/mesh_io.h"
#include "prtlab/geometry/procedural_shapes.h"
#include "prtlab/geometry/uv_mapping.h"
#include "prtlab/storage/data_paths.h"

namespace prt {
namespace fs = std::filesystem;
namespace {

std::string join(const std::set<std::string>& keys) {
  std::string out;
  for (const auto& k : keys) out += (out.empty() ? "" : ", ") + k;
  return out;
}

/// Reports the first key of `table` that is not in `allowed`, naming the valid ones.
void reject_unknown_keys(const fs::path& file, const toml::table& table,
                         const std::set<std::string>& allowed, std::string_view where) {
  for (const auto& [key, node] : table) {
    if (!allowed.contains(std::string(key.str())))
      throw InputError(file,
                       fmt::format("line {}: unknown key '{}' in {} (valid keys: {})",
                                   node.source().begin.line, key.str(), where, join(allowed)));
  }
}

template <typename T>
T require(const fs::path& file, const toml::node_view<const toml::node>& node,
          std::string_view key) {
  auto v = node.value<T>();
  if (!v) {
    if (!node) throw InputError(file, fmt::format("missing required key '{}'", key));
    throw InputError(file, fmt::format("line {}: key '{}' has the wrong type",
                                       node.node()->source().begin.line, key));
  }
  return *v;
}

template <typename T>
std::optional<T> optional_value(const fs::path& file, const toml::node_view<const toml::node>& node,
                                std::string_view key) {
  if (!node) return std::nullopt;
  auto v = node.value<T>();
  if (!v)
    throw InputError(file, fmt::format("line {}: key '{}' has the wrong type",
                                       node.node()->source().begin.line, key));
  return v;
}

Vec3d vec3(const fs::path& file, const toml::node_view<const toml::node>& node,
           std::string_view key, Vec3d fallback) {
  if (!node) return fallback;
  const auto* arr = node.as_array();
  if (!arr || arr->size() != 3)
    throw InputError(file, fmt::format("line {}: key '{}' must be an array of 3 numbers",
                                       node.node()->source().begin.line, key));
  Vec3d out;
  for (int i = 0; i < 3; ++i) {
    auto v = (*arr)[static_cast<std::size_t>(i)].value<double>();
    if (!v) throw InputError(file, fmt::format("key '{}' must hold numbers", key));
    if (!std::isfinite(*v))
      throw InputError(file, fmt::format("line {}: key '{}' holds {} (numbers must be finite)",
                                         node.node()->source().begin.line, key, *v));
    out[i] = *v;
  }
  return out;
}

// Subdivision reaches any target, so an unbounded one runs until memory runs out; the transfer
// matrix of the largest allowed mesh (64 lights per vertex, a few hundred non-zeros each) is
// already tens of GB.
constexpr std::int64_t kMaxTargetVertices = 10'000'000;

void check_target_vertices(const fs::path& file, const std::string& part, std::int64_t tv) {
  const std::string where = part.empty() ? "" : fmt::format("part '{}': ", part);
  if (tv < 4)
    throw InputError(file,
                     fmt::format("{}target_vertices = {} is too small (at least 4)", where, tv));
  if (tv > kMaxTargetVertices)
    throw InputError(file, fmt::format("{}target_vertices = {} is too large (at most {})", where,
                                       tv, kMaxTargetVertices));
}

// A zero scale flattens the part to a plane or a line: every normal becomes undefined, so
// it is refused where the user wrote it, not later in the mesh pipeline.
void require_invertible(const fs::path& file, const std::string& part, std::string_view what,
                        const Transform& xf) {
  const double det = glm::determinant(xf.linear());
  if (!(std::abs(det) > 1e-300) || !std::isfinite(det))
    throw InputError(file, fmt::format("part '{}': {} is singular (scale [{}, {}, {}]; every "
                                       "scale component must be non-zero)",
                                       part, what, xf.scale.x, xf.scale.y, xf.scale.z));
}

int checked_int(const fs::path& file, std::string_view key, std::int64_t v, int lo, int hi) {
  if (v < lo || v > hi)
    throw InputError(file, fmt::format("'{}' = {} is out of range [{}, {}]", key, v, lo, hi));
  return static_cast<int>(v);
}

double param(const ScenePart& part, const std::string& key, double fallback) {
  auto it = part.params.find(key);
  return it == part.params.end() ? fallback : it->second;
}

const std::map<std::string, std::set<std::string>>& procedural_params() {
  static const std::map<std::string, std::set<std::string>> p = {
      {"sphere", {"radius", "segments", "rings"}},
      {"plane", {"size_x", "size_z", "n"}},
      {"box", {"hx", "hy", "hz", "n"}},
      {"torus", {"major_radius", "minor_radius", "segments", "sides"}},
      {"cylinder", {"radius", "height", "segments", "rings"}},
  };
  return p;
}

Mesh make_procedural(const fs::path& file, const ScenePart& part, const std::string& shape) {
  const auto& table = procedural_params();
  auto it = table.find(shape);
  if (it == table.end()) {
    std::set<std::string> names;
    for (const auto& [k, v] : table) names.insert(k);
    throw InputError(file, fmt::format("part '{}': unknown procedural shape '{}' (known: {})",
                                       part.name, shape, join(names)));
  }
  for (const auto& [k, v] : part.params)
    if (!it->second.contains(k))
      throw InputError(
          file, fmt::format("part '{}': unknown parameter '{}' for procedural:{} (valid: {})",
                            part.name, k, shape, join(it->second)));
  auto count = [&](const char* key, double fallback) {
    const double v = param(part, key, fallback);
    if (v < 1 || v > 4096 || v != static_cast<int>(v))
      throw InputError(file, fmt::format("part '{}': '{}' = {} must be an integer in [1, 4096]",
                                         part.name, key, v));
    return static_cast<int>(v);
  };
  auto length = [&](const char* key, double fallback) {
    const double v = param(part, key, fallback);
    if (!(v > 0) || !std::isfinite(v))
      throw InputError(
          file, fmt::format("part '{}': '{}' = {} must be a positive length", part.name, key, v));
    return v;
  };
  if (shape == "sphere")
    return make_sphere(length("radius", 0.5), count("segments", 32), count("rings", 16));
  if (shape == "plane") return make_plane(length("size_x", 1), length("size_z", 1), count("n", 16));
  if (shape == "box")
    return make_box({length("hx", 0.5), length("hy", 0.5), length("hz", 0.5)}, count("n", 8));
  if (shape == "torus")
    return make_torus(length("major_radius", 0.5), length("minor_radius", 0.2),
                      count("segments", 32), count("sides", 16));
  return make_cylinder(length("radius", 0.5), length("height", 1), count("segments", 32),
                       count("rings", 8));
}

/// Generated UVs split vertices along chart borders. Charting the full-resolution mesh and
/// decimating afterwards pins the seams (meshoptimizer collapses seam vertices only along the
/// seam), which spends most of the vertex budget on seams; so the mesh is resampled first and
/// charted after, with the resampling target lowered by the seam copies so that the charted
/// mesh lands slightly above the target; a last, small decimation of the charted mesh (a few
/// interior collapses, which keep the planar UVs exact) removes the rest.
Mesh resample_with_generated_uvs(const Mesh& source, std::optional<std::size_t> target,
                                 const std::string& part_name, bool smooth) {
  UvAtlasReport report;
  if (!target) {
    Mesh out = generate_uvs(source, {}, &report);
    log_debug("part '{}': generated UVs, {} charts, {} -> {} vertices", part_name, report.charts,
              report.input_vertices, report.output_vertices);
    return out;
  }
  const auto want = static_cast<double>(*target);
  constexpr double kAim = 1.01, kWindow = 1.04;  // charted count wanted in [want, 1.04 want]
  double base = want / 1.25;  // charting adds about a quarter in seam copies on scanned meshes
  Mesh above;                 // the smallest charted mesh at or above the target so far
  for (int iter = 0; iter < 8; ++iter) {
    const auto base_count = static_cast<std::size_t>(std::max(4.0, std::round(base)));
    // The base count is only an aim (the last decimation lands on the target), so it may be
    // missed by a little: fragmented models (many small open pieces, whose borders edge
    // collapse keeps) cannot always be decimated to an exact count.
    constexpr double kBaseTolerance = 0.02;
    Mesh charted =
        generate_uvs(base_count == source.vertex_count()
                         ? source
                         : resample_to_vertex_count(source, base_count, kBaseTolerance, smooth),
                     {}, &report);
    const double got = static_cast<double>(charted.vertex_count());
    log_debug("part '{}': resampled to {}, {} charts, {} vertices with seams (target {})",
              part_name, base_count, report.charts, got, want);
    if (got >= want && (above.positions.empty() || charted.vertex_count() < above.vertex_count()))
      above = std::move(charted);
    if (got >= want && got <= kWindow * want) break;
    // Above the source's count resample_to_vertex_count subdivides first (bunny-48k).
    base *= kAim * want / got;
  }
  if (above.positions.empty())
    throw ParameterError(
        fmt::format("part '{}': cannot reach {} vertices with generated UVs (the mesh has {}; "
                    "the seam copies of the charts did not converge)",
                    part_name, *target, source.vertex_count()));
  if (above.vertex_count() == *target) return above;
  return decimate_to_vertex_count(above, *target);
}

/// Shell-style match: `*` any run of characters, `?` one character, everything else literal.
bool glob_match(std::string_view pattern, std::string_view name) {
  std::size_t p = 0, n = 0, star = std::string_view::npos, resume = 0;
  while (n < name.size()) {
    if (p < pattern.size() && (pattern[p] == '?' || pattern[p] == name[n])) {
      ++p, ++n;
    } else if (p < pattern.size() && pattern[p] == '*') {
      star = p++;
      resume = n;
    } else if (star != std::string_view::npos) {
      p = star + 1;
      n = ++resume;
    } else {
      return false;
    }
  }
  while (p < pattern.size() && pattern[p] == '*') ++p;
  return p == pattern.size();
}

/// One model file cut into parts by group: loaded once, and which part took each group.
struct GroupedSource {
  GroupedMesh loaded;
  std::vector<int> owner;  ///< per group: the index of the part that selected it, -1 for none
};

/// The ids of the groups `part` selects; every pattern must match a group no other part has.
std::vector<std::uint16_t> select_groups(const SceneDesc& desc, std::size_t part_index,
                                         const fs::path& mesh_file, GroupedSource& source) {
  const fs::path& scene_file = desc.file;
  const ScenePart& part = desc.parts[part_index];
  const int self = static_cast<int>(part_index);
  const std::vector<std::string>& names = source.loaded.groups;
  std::vector<std::uint16_t> ids;
  for (const std::string& pattern : part.groups) {
    bool matched = false;
    for (std::size_t g = 0; g < names.size(); ++g) {
      if (!glob_match(pattern, names[g])) continue;
      matched = true;
      if (source.owner[g] == self) continue;  // two patterns of this part
      if (source.owner[g] >= 0)
        throw InputError(scene_file,
                         fmt::format("part '{}': group '{}' of {} already belongs to part '{}' "
                                     "(a group can be in one part only)",
                                     part.name, names[g], mesh_file.filename().string(),
                                     desc.parts[static_cast<std::size_t>(source.owner[g])].name));
      source.owner[g] = self;
      ids.push_back(static_cast<std::uint16_t>(g));
    }
    if (!matched) {
      std::string known;
      for (std::size_t g = 0; g < names.size() && g < 40; ++g)
        known += (known.empty() ? "" : ", ") + names[g];
      if (names.size() > 40) known += fmt::format(", ... ({} in all)", names.size());
      throw InputError(scene_file,
                       fmt::format("part '{}': {} has no {} group matching '{}' (its groups: {})",
                                   part.name, mesh_file.string(),
                                   part.group_by == MeshGroupKey::kMaterial ? "material" : "object",
                                   pattern, known));
    }
  }
  return ids;
}

}  // namespace

SceneDesc parse_scene(const fs::path& file) {
  if (!fs::exists(file)) throw InputError(file, "scene file not found");
  toml::table root;
  try {
    root = toml::parse_file(file.string());
  } catch (const toml::parse_error& e) {
    throw InputError(file, fmt::format("line {}, column {}: {}", e.source().begin.line,
                                       e.source().begin.column, e.description()));
  }
  reject_unknown_keys(file, root,
                      {"name", "description", "local_grid", "cubemap_resolution", "supersampling",
                       "target_vertices", "part", "view"},
                      "the scene");
  SceneDesc d;
  d.file = file;
  const toml::node_view<const toml::node> r{root};
  d.name = optional_value<std::string>(file, r["name"], "name").value_or(file.stem().string());
  d.description = optional_value<std::string>(file, r["description"], "description").value_or("");
  d.local_grid = checked_int(
      file, "local_grid",
      optional_value<std::int64_t>(file, r["local_grid"], "local_grid").value_or(8), 1, 64);
  d.cubemap_resolution =
      checked_int(file, "cubemap_resolution",
                  optional_value<std::int64_t>(file, r["cubemap_resolution"], "cubemap_resolution")
                      .value_or(32),
                  1, 256);
  d.supersampling = checked_int(
      file, "supersampling",
      optional_value<std::int64_t>(file, r["supersampling"], "supersampling").value_or(2), 1, 15);
  if (auto tv = optional_value<std::int64_t>(file, r["target_vertices"], "target_vertices")) {
    check_target_vertices(file, "", *tv);
    d.target_vertices = static_cast<std::size_t>(*tv);
  }
  const auto* parts = root["part"].as_array();
  if (!parts || parts->empty())
    throw InputError(file, "the scene has no [[part]] (at least one is required)");
  if (parts->size() > 65535) throw InputError(file, "too many parts (at most 65535)");
  for (const auto& node : *parts) {
    const auto* t = node.as_table();
    if (!t) throw InputError(file, "each [[part]] must be a table");
    reject_unknown_keys(
        file, *t,
        {"name", "mesh", "btf", "uv_scale", "uv_mapping", "target_vertices", "subdivision",
         "groups", "group_by", "transform", "normalize", "params", "instance"},
        "a [[part]]");
    const toml::node_view<const toml::node> p{*t};
    ScenePart part;
    part.name = optional_value<std::string>(file, p["name"], "name")
                    .value_or(fmt::format("part{}", d.parts.size()));
    part.mesh = require<std::string>(file, p["mesh"], "mesh");
    part.btf = optional_value<std::string>(file, p["btf"], "btf").value_or("lambert");
    if (p["uv_scale"].is_array()) {
      const auto* arr = p["uv_scale"].as_array();
      const auto su = arr->size() == 2 ? (*arr)[0].value<double>() : std::nullopt;
      const auto sv = arr->size() == 2 ? (*arr)[1].value<double>() : std::nullopt;
      if (!su || !sv)
        throw InputError(
            file, fmt::format("part '{}': uv_scale must be a number or [su, sv]", part.name));
      part.uv_scale = *su;
      part.uv_scale_v = *sv;
    } else {
      part.uv_scale = optional_value<double>(file, p["uv_scale"], "uv_scale").value_or(1.0);
      part.uv_scale_v = part.uv_scale;
    }
    if (!(part.uv_scale > 0) || !(part.uv_scale_v > 0) || !std::isfinite(part.uv_scale) ||
        !std::isfinite(part.uv_scale_v))
      throw InputError(file, fmt::format("part '{}': uv_scale must be positive", part.name));
    const std::string mapping =
        optional_value<std::string>(file, p["uv_mapping"], "uv_mapping").value_or("auto");
    if (mapping == "auto")
      part.uv_mapping = UvMapping::kAuto;
    else if (mapping == "mesh")
      part.uv_mapping = UvMapping::kMesh;
    else if (mapping == "planar")
      part.uv_mapping = UvMapping::kPlanar;
    else
      throw InputError(file, fmt::format("part '{}': uv_mapping = '{}' (valid: auto, mesh, planar)",
                                         part.name, mapping));
    part.normalize = optional_value<bool>(file, p["normalize"], "normalize").value_or(false);
    if (auto tv = optional_value<std::int64_t>(file, p["target_vertices"], "target_vertices")) {
      check_target_vertices(file, part.name, *tv);
      part.target_vertices = static_cast<std::size_t>(*tv);
    }
    const std::string subdivision =
        optional_value<std::string>(file, p["subdivision"], "subdivision").value_or("loop");
    if (subdivision != "loop" && subdivision != "linear")
      throw InputError(file, fmt::format("part '{}': subdivision = '{}' (valid: loop, linear)",
                                         part.name, subdivision));
    part.smooth_subdivision = subdivision == "loop";
    if (p["groups"]) {
      const auto* arr = p["groups"].as_array();
      if (!arr || arr->empty())
        throw InputError(file, fmt::format("line {}: part '{}': groups must be a non-empty array "
                                           "of group names",
                                           p["groups"].node()->source().begin.line, part.name));
      for (const auto& g : *arr) {
        const auto name = g.value<std::string>();
        if (!name || name->empty())
          throw InputError(file, fmt::format("line {}: part '{}': groups must hold non-empty "
                                             "strings",
                                             g.source().begin.line, part.name));
        part.groups.push_back(*name);
      }
    }
    if (const auto by = optional_value<std::string>(file, p["group_by"], "group_by")) {
      if (part.groups.empty())
        throw InputError(file, fmt::format("part '{}': group_by needs groups = [...]", part.name));
      if (*by == "material")
        part.group_by = MeshGroupKey::kMaterial;
      else if (*by == "object")
        part.group_by = MeshGroupKey::kObject;
      else
        throw InputError(file, fmt::format("part '{}': group_by = '{}' (valid: material, object)",
                                           part.name, *by));
    }
    if (!part.groups.empty() && part.mesh.starts_with("procedural:"))
      throw InputError(file, fmt::format("part '{}': groups are for mesh files; {} has none",
                                         part.name, part.mesh));
    if (const auto* xf = (*t)["transform"].as_table()) {
      reject_unknown_keys(file, *xf, {"scale", "rotate_deg", "translate"}, "a part's transform");
      const toml::node_view<const toml::node> x{*xf};
      part.transform.scale = vec3(file, x["scale"], "scale", Vec3d(1.0));
      part.transform.rotate_deg = vec3(file, x["rotate_deg"], "rotate_deg", Vec3d(0.0));
      part.transform.translate = vec3(file, x["translate"], "translate", Vec3d(0.0));
    } else if (p["transform"]) {
      throw InputError(file, fmt::format("part '{}': transform must be a table", part.name));
    }
    require_invertible(file, part.name, "transform", part.transform);
    if (const auto* params = (*t)["params"].as_table()) {
      for (const auto& [k, v] : *params) {
        auto val = v.value<double>();
        if (!val)
          throw InputError(
              file, fmt::format("part '{}': params.{} must be a number", part.name, k.str()));
        part.params[std::string(k.str())] = *val;
      }
    }
    if (const auto* inst = (*t)["instance"].as_array()) {
      for (const auto& in : *inst) {
        const auto* it = in.as_table();
        if (!it)
          throw InputError(
              file, fmt::format("part '{}': each [[part.instance]] must be a table", part.name));
        reject_unknown_keys(file, *it, {"scale", "translate"}, "a part instance");
        const toml::node_view<const toml::node> x{*it};
        part.instances.push_back({vec3(file, x["scale"], "scale", Vec3d(1.0)),
                                  vec3(file, x["translate"], "translate", Vec3d(0.0))});
        Transform as_transform;
        as_transform.scale = part.instances.back().scale;
        require_invertible(file, part.name, "an instance's scale", as_transform);
      }
    } else if (p["instance"]) {
      throw InputError(file,
                       fmt::format("part '{}': 'instance' must be an array of tables", part.name));
    }
    d.parts.push_back(std::move(part));
  }
  if (const auto* views = root["view"].as_array()) {
    for (const auto& node : *views) {
      const auto* t = node.as_table();
      if (!t) throw InputError(file, "each [[view]] must be a table");
      const int line = static_cast<int>(t->source().begin.line);
      reject_unknown_keys(file, *t, {"name", "eye", "from", "target", "up", "fov", "fill"},
                          "a [[view]]");
      const toml::node_view<const toml::node> v{*t};
      ViewPreset view;
      view.name = require<std::string>(file, v["name"], "name");
      for (const auto& other : d.views)
        if (other.name == view.name)
          throw InputError(file,
                           fmt::format("line {}: view '{}' is defined twice", line, view.name));
      if (v["eye"]) view.eye = vec3(file, v["eye"], "eye", Vec3d(0.0));
      if (v["from"]) view.from = vec3(file, v["from"], "from", Vec3d(0.0));
      if (v["target"]) view.target = vec3(file, v["target"], "target", Vec3d(0.0));
      view.up = vec3(file, v["up"], "up", view.up);
      view.fov_y_deg = optional_value<double>(file, v["fov"], "fov").value_or(view.fov_y_deg);
      view.fill = optional_value<double>(file, v["fill"], "fill").value_or(view.fill);
      try {
        view.validate();
      } catch (const ParameterError& e) {
        throw InputError(file, fmt::format("line {}: {}", line, e.what()));
      }
      d.views.push_back(std::move(view));
    }
  } else if (root["view"]) {
    throw InputError(file, "'view' must be an array of tables ([[view]])");
  }
  if (d.target_vertices && d.parts.size() != 1)
    throw InputError(
        file, "a scene-level 'target_vertices' needs exactly one part (set it per part instead)");
  return d;
}

Scene build_scene(const SceneDesc& desc) {
  Scene scene;
  scene.desc = desc;
  std::map<std::pair<fs::path, MeshGroupKey>, GroupedSource> grouped;
  for (std::size_t i = 0; i < desc.parts.size(); ++i) {
    const ScenePart& part = desc.parts[i];
    Mesh m;
    std::optional<Aabb> normalize_box;
    constexpr std::string_view kProcedural = "procedural:";
    if (part.mesh.starts_with(kProcedural)) {
      m = make_procedural(desc.file, part, part.mesh.substr(kProcedural.size()));
    } else {
      if (!part.params.empty())
        throw InputError(
            desc.file, fmt::format("part '{}': params are only for procedural meshes", part.name));
      const fs::path file = resolve_mesh(part.mesh, desc.file);
      if (part.groups.empty()) {
        m = load_mesh(file);
      } else {
        auto [it, inserted] = grouped.try_emplace({file, part.group_by});
        GroupedSource& source = it->second;
        if (inserted) {
          source.loaded = load_mesh_groups(file, part.group_by);
          source.owner.assign(source.loaded.groups.size(), -1);
        }
        const std::vector<std::uint16_t> ids = select_groups(desc, i, file, source);
        // Exports split vertices at every UV seam and hard edge; per-vertex transfer wants one
        // vertex per surface point, so weld by position unless the file's UVs are kept.
        const bool keep_uvs = part.uv_mapping == UvMapping::kMesh;
        m = weld_vertices(select_parts(source.loaded.mesh, ids),
                          keep_uvs ? WeldKey::kPositionAndUv : WeldKey::kPosition);
        const std::size_t flipped = orient_consistently(m);
        log_debug("part '{}': {} groups, {} vertices after welding, {} triangles flipped",
                  part.name, ids.size(), m.vertex_count(), flipped);
        normalize_box = source.loaded.mesh.bounds();
      }
    }
    auto target = part.target_vertices;
    if (!target && desc.target_vertices) target = desc.target_vertices;
    if (part.uv_mapping == UvMapping::kMesh && !m.has_uvs())
      throw InputError(desc.file, fmt::format("part '{}': uv_mapping = \"mesh\" but {} has no UVs "
                                              "(use \"auto\" or \"planar\")",
                                              part.name, part.mesh));
    if (part.uv_mapping == UvMapping::kPlanar ||
        (part.uv_mapping == UvMapping::kAuto && !m.has_uvs())) {
      m = resample_with_generated_uvs(m, target, part.name, part.smooth_subdivision);
    } else if (target && *target != m.vertex_count()) {
      m = resample_to_vertex_count(m, *target, 0.002, part.smooth_subdivision);
    }
    if (part.normalize) {
      if (normalize_box)
        normalize_to_unit_box(m, /*on_ground=*/true, *normalize_box);
      else
        normalize_to_unit_box(m, /*on_ground=*/true);
    }
    apply_transform(m, part.transform);
    if (part.uv_scale != 1.0 || part.uv_scale_v != 1.0)
      for (auto& uv : m.uvs)
        uv *= Vec2(static_cast<float>(part.uv_scale), static_cast<float>(part.uv_scale_v));
    // Loaded meshes get smooth normals here; procedural shapes keep their analytic ones
    // (recomputing would bend normals at UV-seam duplicates and box edges).
    if (m.normals.size() != m.vertex_count()) compute_smooth_normals(m);
    if (m.tangents.size() != m.vertex_count()) compute_tangents(m);
    if (part.instances.empty()) {
      scene.mesh.append(m, static_cast<std::uint16_t>(i));
    } else {
      for (const auto& inst : part.instances) {
        Mesh copy = m;
        Transform xf;
        xf.scale = inst.scale;
        xf.translate = inst.translate;
        apply_transform(copy, xf);
        scene.mesh.append(copy, static_cast<std::uint16_t>(i));
      }
    }
  }
  for (const auto& [key, source] : grouped) {
    std::size_t unused = 0;
    for (const int owner : source.owner) unused += owner < 0 ? 1 : 0;
    if (unused > 0)
      log_info("{}: {} of its {} groups are in no part (left out)", key.first.string(), unused,
               source.owner.size());
  }
  return scene;
}

ViewPreset scene_view(const SceneDesc& desc, std::string_view name) {
  if (name.empty()) return desc.views.empty() ? automatic_view() : desc.views.front();
  for (const auto& v : desc.views)
    if (v.name == name) return v;
  std::string names;
  for (const auto& v : desc.views) names += (names.empty() ? "" : ", ") + v.name;
  throw ParameterError(
      fmt::format("{}: no view '{}' (presets: {})", desc.file.string(), name,
                  names.empty() ? "none; the automatic view is the default" : names));
}

Camera scene_camera(const Scene& scene, std::string_view view, const CameraOverrides& overrides) {
  const Camera framed = resolve_view(scene_view(scene.desc, view), scene.mesh.positions,
                                     overrides.width.value_or(640), overrides.height.value_or(480));
  return apply_overrides(framed, overrides);
}

}  // namespace prt
