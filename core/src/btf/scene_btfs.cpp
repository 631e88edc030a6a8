#include "prtlab/btf/scene_btfs.h"

#include <map>
#include <string>

namespace prt {

std::vector<std::shared_ptr<const Btf>> scene_part_btfs(const SceneDesc& desc, BtfParams params,
                                                        StageCache& cache, bool show_progress,
                                                        int* cache_hits) {
  params.light_side = desc.local_grid;
  std::map<std::string, std::shared_ptr<const Btf>> by_name;
  std::vector<std::shared_ptr<const Btf>> out;
  if (cache_hits) *cache_hits = 0;
  for (const ScenePart& part : desc.parts) {
    auto it = by_name.find(part.btf);
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
