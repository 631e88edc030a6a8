#include "experiment_spec.h"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <set>

#include "point_measurement.h"
#include "prtlab/base/build_info.h"
#include "prtlab/base/error.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/compress/light_options.h"
#include "prtlab/compress/params.h"
#include "prtlab/storage/data_paths.h"

namespace prt::experiments {
namespace {
namespace fs = std::filesystem;

const std::vector<std::string> kBlenderWorlds = {"city",  "courtyard", "forest",  "interior",
                                                 "night", "studio",    "sunrise", "sunset"};

const std::set<std::string> kTopKeys = {"name",        "title",        "kind",
                                        "scenes",      "scene_grid",   "backends",
                                        "exclude",     "params",       "grid",
                                        "knob_points", "environments", "views",
                                        "image",       "btf",          "repeats",
                                        "timing",      "images",       "fps",
                                        "fps_frames",  "reference",    "target",
                                        "paper",       "paper_source", "variant",
                                        "points",      "curves",       "frobenius_relights"};
const std::set<std::string> kCurveKeys = {"backend", "x",     "y",     "series",
                                          "panel",   "log_x", "log_y", "title"};

std::string join(const auto& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : ", ") + std::string(s);
  return out;
}

// "line N: " for a node parsed from the file; nodes keep their source only when moved, never
// when copied (toml++), so parse_experiment moves the variant's keys into place.
std::string line_of(const toml::node& n) {
  const auto line = n.source().begin.line;
  return line > 0 ? fmt::format("line {}: ", line) : std::string();
}

// The value of a scalar node as a parameter string ("3", "0.05", "true", "lanes").
std::string scalar_string(const fs::path& file, const toml::node& n, std::string_view key) {
  if (auto v = n.value_exact<std::int64_t>()) return std::to_string(*v);
  if (auto v = n.value_exact<double>()) return fmt::format("{}", *v);
  if (auto v = n.value_exact<bool>()) return *v ? "true" : "false";
  if (auto v = n.value_exact<std::string>()) return *v;
  throw InputError(file,
                   line_of(n) + fmt::format("'{}' must be a number, a boolean or a string", key));
}

std::vector<std::string> string_list(const fs::path& file, const toml::node& n,
                                     std::string_view key) {
  std::vector<std::string> out;
  if (auto s = n.value_exact<std::string>()) return {*s};
  const auto* arr = n.as_array();
  if (!arr) throw InputError(file, line_of(n) + fmt::format("'{}' must be a list of strings", key));
  for (const auto& e : *arr) {
    auto s = e.value_exact<std::string>();
    if (!s) throw InputError(file, line_of(e) + fmt::format("'{}' must hold strings", key));
    out.push_back(*s);
  }
  return out;
}

template <typename T>
T scalar(const fs::path& file, const toml::node& n, std::string_view key) {
  if constexpr (std::is_same_v<T, double>) {
    if (auto v = n.value<double>()) return *v;
  } else {
    if (auto v = n.value_exact<T>()) return *v;
  }
  throw InputError(file, line_of(n) + fmt::format("'{}' has the wrong type", key));
}

int int_in(const fs::path& file, const toml::node& n, std::string_view key, int lo, int hi) {
  const auto v = scalar<std::int64_t>(file, n, key);
  if (v < lo || v > hi)
    throw InputError(file, line_of(n) + fmt::format("'{}' = {} is outside {}..{}", key, v, lo, hi));
  return static_cast<int>(v);
}

std::map<std::string, std::string> param_table(const fs::path& file, const toml::node& n,
                                               std::string_view key) {
  const auto* t = n.as_table();
  if (!t) throw InputError(file, line_of(n) + fmt::format("'{}' must be a table", key));
  std::map<std::string, std::string> out;
  for (const auto& [k, v] : *t) out[std::string(k.str())] = scalar_string(file, v, k.str());
  return out;
}

// `base` with the keys of `over` replacing its own (a variant replaces whole keys). Both are
// moved from, so every node keeps the line it was read from.
void apply_variant(toml::table& base, toml::table&& over) {
  for (auto&& [k, v] : over) base.insert_or_assign(k, std::move(v));
}

toml::table load_table(const fs::path& file) {
  if (!fs::exists(file)) throw InputError(file, "no such experiment file");
  try {
    return toml::parse_file(file.string());
  } catch (const toml::parse_error& e) {
    throw InputError(file, fmt::format("line {}: {}", e.source().begin.line, e.description()));
  }
}

// The table under `key`, nullptr when absent; an InputError when the key holds something else.
const toml::table* table_at(const fs::path& file, const toml::table& t, std::string_view key) {
  const toml::node* n = t.get(key);
  if (!n) return nullptr;
  const auto* table = n->as_table();
  if (!table) throw InputError(file, line_of(*n) + fmt::format("'{}' must be a table", key));
  return table;
}

void check_keys(const fs::path& file, const toml::table& t, const std::set<std::string>& allowed,
                std::string_view where) {
  for (const auto& [k, v] : t)
    if (!allowed.contains(std::string(k.str())))
      throw InputError(file, line_of(v) + fmt::format("unknown key '{}' in {} (valid: {})", k.str(),
                                                      where, join(allowed)));
}

}  // namespace

EnvironmentSpec parse_environment(const fs::path& file, const std::string& name) {
  EnvironmentSpec e;
  // "sun", "sun:RATIO" or "sun-RATIO" (not "sunset", a Blender world).
  const bool only = name.starts_with("sunonly");
  const std::size_t stem = only ? 7 : 3;
  const bool sun = name == "sun" || name == "sunonly" || name.starts_with("sun:") ||
                   name.starts_with("sunonly:") ||
                   (name.starts_with("sun-") && name.size() > 4 &&
                    std::isdigit(static_cast<unsigned char>(name[4])));
  if (sun) {
    double ratio = 3e4;
    if (name.size() > stem) {
      try {
        std::size_t used = 0;
        ratio = std::stod(name.substr(stem + 1), &used);
        if (used != name.size() - stem - 1) throw std::invalid_argument("trailing");
      } catch (const std::exception&) {
        throw InputError(file, fmt::format("environment '{}': '{}' is not a number", name,
                                           name.substr(stem + 1)));
      }
    }
    if (!(ratio > 0) || !std::isfinite(ratio))
      throw InputError(file, fmt::format("environment '{}': the sun ratio must be > 0", name));
    e.sun_ratio = ratio;
    e.sun_only = only;
    e.name = fmt::format("{}-{:g}", only ? "sunonly" : "sun", ratio);
    return e;
  }
  try {
    e.file = resolve_envmap(name).string();
  } catch (const Error& err) {
    throw InputError(file, fmt::format("environment '{}': {}", name, err.what()));
  }
  e.name = fs::path(name).stem().string();
  return e;
}

const std::vector<std::string>& experiment_kinds() {
  static const std::vector<std::string> kinds = {"equal_storage", "sweep", "material_table",
                                                 "stability"};
  return kinds;
}

std::string_view to_string(ExperimentKind k) {
  return k == ExperimentKind::kEqualStorage ? "equal_storage" : "sweep";
}

nlohmann::json evaluation_json(const ExperimentSpec& s) {
  nlohmann::json envs = nlohmann::json::array();
  for (const auto& e : s.environments)
    envs.push_back(
        {{"name", e.name},
         {"file", e.file},
         {"sun_ratio", e.sun_ratio ? nlohmann::json(*e.sun_ratio) : nlohmann::json(nullptr)},
         {"sun_only", e.sun_only}});
  return {{"environments", envs},
          {"views", s.views},
          {"width", s.width},
          {"height", s.height},
          {"repeats", s.repeats},
          {"frobenius_relights", s.frobenius_relights},
          {"timing", s.timing},
          {"images", s.images},
          {"fps", s.fps},
          {"fps_frames", s.fps_frames},
          {"btf_resolution", s.btf_resolution},
          {"btf_view_side", s.btf_view_side},
          {"reference", s.reference}};
}

nlohmann::json to_json(const ExperimentSpec& s) {
  nlohmann::json j = evaluation_json(s);
  j.update({{"file", s.file.string()},
            {"name", s.name},
            {"title", s.title},
            {"variant", s.variant},
            {"kind", to_string(s.kind)},
            {"scenes", s.scenes},
            {"scene_grid", s.scene_grid},
            {"backends", s.backends},
            {"params", s.params},
            {"grid", s.grid},
            {"points", s.points},
            {"knob_points", s.knob_points}});
  nlohmann::json curves = nlohmann::json::array();
  for (const CurveSpec& c : s.curves)
    curves.push_back({{"backend", c.backend},
                      {"x", c.x},
                      {"y", c.y},
                      {"series", c.series},
                      {"panel", c.panel},
                      {"log_x", c.log_x},
                      {"log_y", c.log_y},
                      {"title", c.title}});
  j["curves"] = curves;
  if (s.kind == ExperimentKind::kEqualStorage)
    j["target"] = {{"backend", s.target.backend},
                   {"params", s.target.params},
                   {"megabytes", s.target.megabytes ? nlohmann::json(*s.target.megabytes)
                                                    : nlohmann::json(nullptr)},
                   {"tolerance", s.target.tolerance},
                   {"max_probes", s.target.max_probes}};
  return j;
}

std::string declared_kind(const fs::path& file) {
  try {
    const toml::table t = toml::parse_file(file.string());
    return t["kind"].value_or(std::string());
  } catch (...) {
    return {};
  }
}

std::vector<std::string> declared_variants(const fs::path& file) {
  std::vector<std::string> out;
  try {
    const toml::table t = toml::parse_file(file.string());
    if (const auto* v = t["variant"].as_table())
      for (const auto& [k, unused] : *v) out.emplace_back(k.str());
  } catch (...) {
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::string> experiment_variants(const fs::path& file) {
  const toml::table root = load_table(file);
  std::vector<std::string> out;
  if (const auto* v = root["variant"].as_table())
    for (const auto& [k, _] : *v) out.emplace_back(k.str());
  return out;
}

ExperimentSpec parse_experiment(const fs::path& file, const std::string& variant,
                                const std::vector<std::string>& registered) {
  toml::table t = load_table(file);
  check_keys(file, t, kTopKeys, "the experiment");
  if (!variant.empty() &&
      variant.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789-_") != std::string::npos)
    throw InputError(file, fmt::format("variant '{}': use lower-case letters, digits, '-' and "
                                       "'_' (it names the result folder)",
                                       variant));
  if (!variant.empty()) {
    auto* variants = t["variant"].as_table();
    auto* chosen = variants ? (*variants)[variant].as_table() : nullptr;
    if (!chosen)
      throw InputError(file, fmt::format("no variant '{}' (declared: {})", variant,
                                         variants ? join(experiment_variants(file)) : "none"));
    check_keys(file, *chosen, kTopKeys, fmt::format("[variant.{}]", variant));
    toml::table over = std::move(*chosen);
    t.erase("variant");
    apply_variant(t, std::move(over));
  }
  t.erase("variant");

  ExperimentSpec s;
  s.file = file;
  s.variant = variant;
  const auto* name = t["name"].node();
  if (!name) throw InputError(file, "missing required key 'name'");
  s.name = scalar<std::string>(file, *name, "name");
  if (s.name.empty() ||
      s.name.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789-_") != std::string::npos)
    throw InputError(file, fmt::format("name '{}': use lower-case letters, digits, '-' and '_' "
                                       "(it names the result folder)",
                                       s.name));
  s.title = t["title"] ? scalar<std::string>(file, *t["title"].node(), "title") : s.name;
  if (const auto* k = t["kind"].node()) {
    const auto kind = scalar<std::string>(file, *k, "kind");
    if (kind == "equal_storage")
      s.kind = ExperimentKind::kEqualStorage;
    else if (kind == "sweep")
      s.kind = ExperimentKind::kSweep;
    else
      throw InputError(file, line_of(*k) + fmt::format("unknown kind '{}' (kinds: {})", kind,
                                                       join(experiment_kinds())));
  }
  const auto* scenes = t["scenes"].node();
  if (!scenes) throw InputError(file, "missing required key 'scenes'");
  s.scenes = string_list(file, *scenes, "scenes");
  if (s.scenes.empty()) throw InputError(file, "'scenes' is empty");
  if (const auto* g = table_at(file, t, "scene_grid")) {
    for (const auto& [k, v] : *g) {
      const std::string key(k.str());
      if (key != "local_grid" && key != "cubemap_resolution" && key != "supersampling")
        throw InputError(file, line_of(v) + fmt::format("scene_grid key '{}': only local_grid, "
                                                        "cubemap_resolution and supersampling "
                                                        "can be swept",
                                                        key));
      const auto* arr = v.as_array();
      if (!arr || arr->empty())
        throw InputError(file, line_of(v) + fmt::format("scene_grid.{} must be a non-empty list "
                                                        "of integers",
                                                        key));
      // The scene file's own limits (docs/scenes.md), so a bad value fails before any stage.
      const int hi = key == "local_grid" ? 64 : key == "cubemap_resolution" ? 256 : 15;
      for (const auto& e : *arr) s.scene_grid[key].push_back(int_in(file, e, key, 1, hi));
    }
  }

  // Backends: "*" is every registered one; the default too.
  std::vector<std::string> listed = {"*"};
  if (const auto* b = t["backends"].node()) listed = string_list(file, *b, "backends");
  if (const auto* e = t["exclude"].node()) s.exclude = string_list(file, *e, "exclude");
  const auto& registry = CompressorRegistry::instance();
  // Excluding a backend that is not registered is harmless (a plugin not loaded this time).
  // A name listed twice (or beside "*", which lists every backend) would measure the same
  // points twice or silently merge two parameter sets: refused.
  const std::string where = t["backends"] ? line_of(*t["backends"].node()) : std::string();
  for (std::size_t i = 0; i < listed.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (listed[i] == listed[j])
        throw InputError(file, where + fmt::format("backend '{}' is listed twice in 'backends' "
                                                   "(each backend runs once; give one entry)",
                                                   listed[i]));
  if (listed.size() > 1 && std::ranges::count(listed, "*") > 0)
    throw InputError(file, where +
                               "'*' already lists every registered backend: give '*' alone, "
                               "or name the backends (use 'exclude' to leave some out)");
  for (const auto& b : listed) {
    if (b == "*") {
      for (const auto& r : registered)
        if (std::find(s.backends.begin(), s.backends.end(), r) == s.backends.end())
          s.backends.push_back(r);
      continue;
    }
    if (!registry.contains(b))
      throw InputError(file, fmt::format("backend '{}' is not registered (known: {}; a plugin's "
                                         "backend needs --plugin)",
                                         b, join(registered)));
    if (std::find(s.backends.begin(), s.backends.end(), b) == s.backends.end())
      s.backends.push_back(b);
  }
  std::erase_if(s.backends, [&](const std::string& b) {
    return std::find(s.exclude.begin(), s.exclude.end(), b) != s.exclude.end();
  });
  if (s.backends.empty()) throw InputError(file, "no backends left to run");

  if (const auto* p = table_at(file, t, "params"))
    for (const auto& [k, v] : *p) s.params[std::string(k.str())] = param_table(file, v, k.str());
  if (const auto* g = table_at(file, t, "grid")) {
    for (const auto& [b, tab] : *g) {
      const auto* bt = tab.as_table();
      if (!bt)
        throw InputError(file, line_of(tab) + fmt::format("grid.{} must be a table", b.str()));
      for (const auto& [k, v] : *bt) {
        const auto* arr = v.as_array();
        if (!arr || arr->empty())
          throw InputError(file, line_of(v) + fmt::format("grid.{}.{} must be a non-empty list",
                                                          b.str(), k.str()));
        auto& values = s.grid[std::string(b.str())][std::string(k.str())];
        for (const auto& e : *arr) values.push_back(scalar_string(file, e, k.str()));
      }
    }
  }
  if (const auto* pt = table_at(file, t, "points")) {
    for (const auto& [b, list] : *pt) {
      const auto* arr = list.as_array();
      if (!arr || arr->empty())
        throw InputError(file, line_of(list) + fmt::format("points.{} must be a non-empty list of "
                                                           "parameter tables ([[points.{}]])",
                                                           b.str(), b.str()));
      if (s.grid.contains(std::string(b.str())))
        throw InputError(file, line_of(list) + fmt::format("backend {} has both a grid and "
                                                           "points: give one",
                                                           b.str()));
      for (const auto& e : *arr)
        s.points[std::string(b.str())].push_back(param_table(file, e, b.str()));
    }
  }
  if (const auto* cv = t.get("curves")) {
    const auto* arr = cv->as_array();
    if (!arr) throw InputError(file, line_of(*cv) + "curves must be a list of tables ([[curves]])");
    for (const auto& e : *arr) {
      const auto* ct = e.as_table();
      if (!ct) throw InputError(file, line_of(e) + "each [[curves]] entry must be a table");
      check_keys(file, *ct, kCurveKeys, "a curve");
      CurveSpec c;
      const auto str = [&](const char* key, std::string& out, bool required) {
        const toml::node* n = ct->get(key);
        if (!n) {
          if (required) throw InputError(file, line_of(e) + fmt::format("a curve needs '{}'", key));
          return;
        }
        auto v = n->value_exact<std::string>();
        if (!v)
          throw InputError(file, line_of(*n) + fmt::format("curve '{}' must be a string", key));
        out = *v;
      };
      const auto flag = [&](const char* key, bool& out) {
        if (const toml::node* n = ct->get(key)) {
          auto v = n->value_exact<bool>();
          if (!v)
            throw InputError(file, line_of(*n) + fmt::format("curve '{}' must be a boolean", key));
          out = *v;
        }
      };
      str("backend", c.backend, true);
      str("x", c.x, true);
      str("y", c.y, false);
      str("series", c.series, false);
      str("panel", c.panel, false);
      str("title", c.title, false);
      flag("log_x", c.log_x);
      flag("log_y", c.log_y);
      if (registry.contains(c.backend)) {
        const auto& entry = registry.get(c.backend);
        const std::vector<ParamSpec> point_specs = point_param_specs(entry);
        for (const std::string* key : {&c.x, &c.series, &c.panel}) {
          if (key->empty()) continue;
          const bool known =
              std::any_of(point_specs.begin(), point_specs.end(),
                          [&](const ParamSpec& p) { return p.key == *key; }) ||
              (key == &c.x && (std::ranges::count(point_record_columns(), *key) > 0 ||
                               key->starts_with("metrics.")));
          if (!known)
            throw InputError(
                file,
                line_of(e) +
                    fmt::format("curve: '{}' is not a parameter of {}{}", *key, c.backend,
                                key == &c.x ? " nor a points.csv column nor metrics.<name>" : ""));
        }
      }
      s.curves.push_back(std::move(c));
    }
  }
  // Parameters of backends that exist are validated now (a typo costs nothing); those of a
  // backend that is not registered (a plugin not loaded this time) are left alone.
  // A point's parameters may hold the backend's light options (light_options.h) beside its
  // compression parameters.
  for (const auto& b : s.backends) {
    const auto& entry = registry.get(b);
    std::map<std::string, std::string> probe =
        s.params.contains(b) ? s.params.at(b) : std::map<std::string, std::string>{};
    const auto validate = [&](const std::map<std::string, std::string>& point) {
      const PointParams split = split_point_params(entry, point);
      (void)ParamSet(b, entry.params, split.compression);
      (void)registry.light_options(b, split.light);
    };
    try {
      validate(probe);
      if (s.points.contains(b))
        for (const auto& point : s.points.at(b)) {
          auto with = probe;
          for (const auto& [k, v] : point) with[k] = v;
          validate(with);
        }
      if (s.grid.contains(b))
        for (const auto& [k, values] : s.grid.at(b))
          for (const auto& v : values) {
            auto with = probe;
            with[k] = v;
            validate(with);
          }
    } catch (const Error& e) {
      throw InputError(file, e.what());
    }
  }
  if (const auto* k = t["knob_points"].node())
    s.knob_points = int_in(file, *k, "knob_points", 1, 1000);

  std::vector<std::string> envs = {"courtyard"};
  if (const auto* e = t["environments"].node()) envs = string_list(file, *e, "environments");
  for (const auto& env : envs) {
    if (env == "blender") {
      for (const auto& w : kBlenderWorlds) s.environments.push_back(parse_environment(file, w));
      continue;
    }
    s.environments.push_back(parse_environment(file, env));
  }
  if (s.environments.empty()) throw InputError(file, "'environments' is empty");
  // Names key the per-environment errors, images and plots: two environments of one name
  // would overwrite each other.
  for (std::size_t i = 0; i < s.environments.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (s.environments[i].name == s.environments[j].name)
        throw InputError(file,
                         fmt::format("environment '{}' is listed twice", s.environments[i].name));
  if (const auto* v = t["views"].node()) s.views = string_list(file, *v, "views");
  if (const auto* img = table_at(file, t, "image")) {
    check_keys(file, *img, {"width", "height"}, "image");
    if (const auto* w = (*img)["width"].node()) s.width = int_in(file, *w, "image.width", 8, 8192);
    if (const auto* h = (*img)["height"].node())
      s.height = int_in(file, *h, "image.height", 8, 8192);
  }
  if (const auto* btf = table_at(file, t, "btf")) {
    check_keys(file, *btf, {"resolution", "view_side"}, "btf");
    if (const auto* r = (*btf)["resolution"].node())
      s.btf_resolution = int_in(file, *r, "btf.resolution", 1, 1024);
    if (const auto* v = (*btf)["view_side"].node())
      s.btf_view_side = int_in(file, *v, "btf.view_side", 1, 64);
  }
  if (const auto* r = t["repeats"].node()) s.repeats = int_in(file, *r, "repeats", 1, 100000);
  if (const auto* r = t["frobenius_relights"].node())
    s.frobenius_relights = int_in(file, *r, "frobenius_relights", 0, 100000);
  if (const auto* v = t["timing"].node()) s.timing = scalar<bool>(file, *v, "timing");
  if (const auto* v = t["images"].node()) s.images = scalar<bool>(file, *v, "images");
  if (const auto* v = t["fps"].node()) s.fps = scalar<bool>(file, *v, "fps");
  if (const auto* v = t["fps_frames"].node())
    s.fps_frames = int_in(file, *v, "fps_frames", 2, 10000);
  if (const auto* v = t["reference"].node()) {
    s.reference = scalar<std::string>(file, *v, "reference");
    if (!registry.contains(s.reference))
      throw InputError(file, fmt::format("reference backend '{}' is not registered", s.reference));
  }
  if (const auto* tg = table_at(file, t, "target")) {
    check_keys(file, *tg, {"backend", "params", "megabytes", "tolerance", "max_probes"}, "target");
    if (const auto* b = (*tg)["backend"].node())
      s.target.backend = scalar<std::string>(file, *b, "target.backend");
    if (const auto* p = (*tg)["params"].node())
      s.target.params = param_table(file, *p, "target.params");
    if (const auto* m = (*tg)["megabytes"].node()) {
      s.target.megabytes = scalar<double>(file, *m, "target.megabytes");
      if (!(*s.target.megabytes > 0))
        throw InputError(file, line_of(*m) + "target.megabytes must be > 0");
    }
    if (const auto* tol = (*tg)["tolerance"].node()) {
      s.target.tolerance = scalar<double>(file, *tol, "target.tolerance");
      if (!(s.target.tolerance > 0 && s.target.tolerance < 1))
        throw InputError(file, line_of(*tol) + "target.tolerance must be in (0, 1)");
    }
    if (const auto* mp = (*tg)["max_probes"].node())
      s.target.max_probes = int_in(file, *mp, "target.max_probes", 2, 200);
  }
  if (s.kind == ExperimentKind::kEqualStorage && !s.target.megabytes &&
      !registry.contains(s.target.backend))
    throw InputError(file, fmt::format("target backend '{}' is not registered", s.target.backend));
  if (s.kind == ExperimentKind::kEqualStorage && !s.target.megabytes) {
    try {
      (void)ParamSet(s.target.backend, registry.get(s.target.backend).params, s.target.params);
    } catch (const Error& e) {
      throw InputError(file, fmt::format("target.params: {}", e.what()));
    }
  }
  if (const auto* p = table_at(file, t, "paper"))
    for (const auto& [k, v] : *p)
      s.paper[std::string(k.str())] = scalar<std::string>(file, v, k.str());
  if (const auto* ps = t["paper_source"].node())
    s.paper_source = scalar<std::string>(file, *ps, "paper_source");
  return s;
}

std::vector<fs::path> experiment_files() {
  const fs::path root = build_info().source_dir;
  std::vector<fs::path> top, backends;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(root / "experiments", ec))
    if (e.path().extension() == ".toml") top.push_back(e.path());
  for (const auto& dir : fs::directory_iterator(root / "compressors", ec)) {
    std::error_code ec2;
    for (const auto& e : fs::directory_iterator(dir.path() / "experiments", ec2))
      if (e.path().extension() == ".toml") backends.push_back(e.path());
  }
  std::sort(top.begin(), top.end());
  std::sort(backends.begin(), backends.end());
  top.insert(top.end(), backends.begin(), backends.end());
  return top;
}

fs::path resolve_experiment(const std::string& name_or_path) {
  const fs::path p(name_or_path);
  if (p.extension() == ".toml" || name_or_path.find('/') != std::string::npos) {
    if (!fs::exists(p)) throw InputError(p, "no such experiment file");
    return p;
  }
  std::vector<std::string> known;
  for (const auto& f : experiment_files()) {
    if (f.stem() == name_or_path) return f;
    known.push_back(f.stem().string());
  }
  throw ParameterError(fmt::format("experiment '{}' not found (known: {}; or give a .toml path)",
                                   name_or_path, join(known)));
}

}  // namespace prt::experiments
