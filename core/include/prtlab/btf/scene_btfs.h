#pragma once
// The BTF of every part of a scene, generated through the stage cache once per distinct
// material (docs/btf.md). Shared by the backends that declare they need BTFs
// (compress/backend_input.h) and by the frame loop's materials.
#include <memory>
#include <vector>

#include "prtlab/btf/btf_generator.h"
#include "prtlab/geometry/scene.h"

namespace prt {

/// Checks that every part's btf names a BTF material or an existing file (relative to the scene
/// file's folder), without generating or reading any; throws an InputError naming the scene file.
void check_scene_btf_names(const SceneDesc& desc);

/// generate_btf_cached(part.btf, params with light_side = desc.local_grid) per distinct part
/// material, in part order. `cache_hits` (optional) counts the materials from the cache.
std::vector<std::shared_ptr<const Btf>> scene_part_btfs(const SceneDesc& desc, BtfParams params,
                                                        StageCache& cache,
                                                        bool show_progress = false,
                                                        int* cache_hits = nullptr);

}  // namespace prt
