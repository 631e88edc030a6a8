#include "prtlab/btf/scene_btfs.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <filesystem>
#include <map>
#include <string>

#include "prtlab/base/error.h"
#include "prtlab/btf/btf_generator.h"
#include "prtlab/btf/btf_materials.h"

namespace prt {

namespace fs = std::filesystem;

namespace {

// A BTF file is relative to the scene file's folder.
fs::path scene_btf_file(const SceneDesc& desc, const ScenePart& part) {
  fs::path file = part.btf;
  if (file.is_relative() && !desc.file.empty()) file = desc.file.parent_path() / file;
  return file;
}

void check_btf_name(const SceneDesc& desc, const ScenePart& part) {
  if (is_btf_material(part.btf)) return;
  const fs::path file = scene_btf_file(desc, part);
  std::error_code ec;
  if (!fs::is_regular_file(file, ec))
    throw InputError(desc.file, fmt::format("part '{}': btf '{}' is neither a BTF material "
                                            "({}) nor a file ({} does not exist)",
                                            part.name, part.btf,
                                            fmt::join(btf_material_names(), ", "), file.string()));
}

}  // namespace

void check_scene_btf_names(const SceneDesc& desc) {
  for (const ScenePart& part : desc.parts) check_btf_name(desc, part);
}

std::vector<std::shared_ptr<const Btf>> scene_part_btfs(const SceneDesc& desc, BtfParams params,
                                                        StageCache& cache, bool show_progress,
                                                        int* cache_hits) {
  params.light_side = desc.local_grid;
  std::map<std::string, std::shared_ptr<const Btf>> by_name;
  std::vector<std::shared_ptr<const Btf>> out;
  if (cache_hits) *cache_hits = 0;
  for (const ScenePart& part : desc.parts) {
    auto it = by_name.find(part.btf);
    if (it == by_name.end() && !is_btf_material(part.btf)) {
      // A BTF file (a measured one from `prtlab btf import`, or any written BTF), relative to
      // the scene file's folder: it is used at its own texels and views, but its lights must
      // be the scene's local grid, which shading indexes.
      check_btf_name(desc, part);
      const fs::path file = scene_btf_file(desc, part);
      std::shared_ptr<const Btf> btf;
      try {
        btf = std::make_shared<const Btf>(read_btf(file));
      } catch (const Error& e) {
        // The BTF file's own error names it; the scene file is where the user chose it.
        throw InputError(desc.file,
                         fmt::format("part '{}': btf '{}': {}", part.name, part.btf, e.what()));
      }
      if (btf->light_side() != desc.local_grid)
        throw InputError(file, fmt::format("its light side is {}, the scene's local grid is {} "
                                           "(import it with --light-side {})",
                                           btf->light_side(), desc.local_grid, desc.local_grid));
      it = by_name.emplace(part.btf, std::move(btf)).first;
    }
    if (it == by_name.end()) {
      BtfStageResult r =
          generate_btf_cached(part.btf, params, cache, CacheMode::kUse, show_progress);
      if (cache_hits && r.cache_hit) ++*cache_hits;
      it = by_name.emplace(part.btf, std::make_shared<const Btf>(std::move(r.btf))).first;
    }
    out.push_back(it->second);
  }
  return out;
}

}  // namespace prt
