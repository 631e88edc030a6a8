#include "prtlab/compress/backend_input.h"

#include <fmt/format.h>

#include <algorithm>

#include "prtlab/base/error.h"
#include "prtlab/btf/scene_btfs.h"
#include "prtlab/compress/brdf_signal.h"

namespace prt {

BackendInputs union_of(std::span<const BackendInputs> needs) {
  BackendInputs u;
  for (const auto& n : needs) {
    u.sh_order = std::max(u.sh_order, n.sh_order);
    u.mesh = u.mesh || n.mesh;
    u.btfs = u.btfs || n.btfs;
    u.brdf_signal = u.brdf_signal || n.brdf_signal;
  }
  return u;
}

std::string describe(const BackendInputs& n) {
  std::string s = "T";
  if (n.sh_order > 0) s += fmt::format(", SH order {}", n.sh_order);
  if (n.mesh) s += ", mesh";
  if (n.btfs) s += ", BTFs";
  if (n.brdf_signal) s += ", BRDF-weighted signal";
  return s;
}

PreparedScene prepare_scene(const SceneDesc& desc, const BackendInputs& needs, StageCache& cache,
                            const PrepareOptions& options) {
  PreparedScene p;
  p.desc = desc;
  PrecomputeOptions popt;
  popt.sh_order = needs.sh_order;
  popt.cache = options.cache;
  popt.show_progress = options.show_progress;
  p.transfer = precompute_scene_transfer(desc, popt, cache);
  p.cubemap = CubemapLayout(desc.cubemap_resolution);
  p.grid = HemisphereGrid(desc.local_grid);
  if (needs.mesh || needs.btfs) {
    Scene scene = build_scene(desc);
    if (scene.mesh.positions.size() != p.transfer.result.transfer.vertex_count())
      throw Error(fmt::format(
          "scene '{}': the built mesh has {} vertices but its cached transfer has {} (stale "
          "stage cache? rerun prtlab precompute --force)",
          desc.name, scene.mesh.positions.size(), p.transfer.result.transfer.vertex_count()));
    p.mesh = std::move(scene.mesh);
  }
  if (needs.brdf_signal) p.brdf_signal = std::make_shared<BrdfSignalSource>();
  if (needs.btfs)
    p.btfs = scene_part_btfs(desc, options.btf, cache, options.show_progress, &p.btf_cache_hits);
  return p;
}

PreparedScene prepare_scene_for(const SceneDesc& desc, std::span<const std::string> backends,
                                StageCache& cache, const PrepareOptions& options) {
  std::vector<BackendInputs> needs;
  for (const auto& name : backends)
    needs.push_back(CompressorRegistry::instance().get(name).inputs);
  return prepare_scene(desc, union_of(needs), cache, options);
}

TransferInput PreparedScene::input(const CompressorEntry& entry) const {
  const auto& sh = transfer.result.sh;
  auto missing = [&](const std::string& what) {
    return ParameterError(fmt::format(
        "backend '{}' needs {}, which the preparation of scene '{}' did not include (prepare "
        "it with prepare_scene_for the backends it runs)",
        entry.name, what, desc.name));
  };
  if (entry.inputs.sh_order > 0 && (!sh || sh->order() < entry.inputs.sh_order))
    throw missing(fmt::format("the SH transfer of order {}", entry.inputs.sh_order));
  if (entry.inputs.mesh && !mesh) throw missing("the mesh");
  if (entry.inputs.btfs && btfs.empty()) throw missing("the BTFs");
  if (entry.inputs.brdf_signal && !brdf_signal) throw missing("the BRDF-weighted signal");
  return TransferInput{transfer.result.transfer,
                       entry.inputs.sh_order > 0 ? &*sh : nullptr,
                       cubemap,
                       grid,
                       entry.inputs.mesh ? &*mesh : nullptr,
                       entry.inputs.btfs ? std::span<const std::shared_ptr<const Btf>>(btfs)
                                         : std::span<const std::shared_ptr<const Btf>>(),
                       entry.inputs.brdf_signal ? brdf_signal.get() : nullptr};
}

}  // namespace prt
