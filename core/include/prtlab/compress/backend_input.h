#pragma once
// One function prepares, for one scene, what a set of backends declare they need
// (CompressorEntry::inputs): T always, the SH transfer at the largest order asked, the mesh,
// the BTFs, the BRDF-weighted signal (folded on first use). Every stage goes through the stage
// cache. Callers (the CLI, the experiments, the benches) list backends and never special-case one.
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "prtlab/btf/btf_generator.h"
#include "prtlab/compress/brdf_signal.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/geometry/scene.h"
#include "prtlab/transfer/scene_transfer.h"

namespace prt {

struct PrepareOptions {
  bool show_progress = true;
  CacheMode cache = CacheMode::kUse;  ///< for T (kRefresh recomputes it)
  BtfParams btf;                      ///< when a backend asks for BTFs (light_side = the scene's S)
};

/// What prepare_scene() built. Movable; input() views into it.
struct PreparedScene {
  SceneDesc desc;
  SceneTransfer transfer;  ///< T, and the SH transfer at the largest order asked (if any)
  CubemapLayout cubemap{1};
  HemisphereGrid grid{1};
  std::optional<Mesh> mesh;
  std::vector<std::shared_ptr<const Btf>> btfs;
  int btf_cache_hits = 0;
  /// When a backend asks for the BRDF-weighted signal: the folded rows, built on first use.
  std::shared_ptr<BrdfSignalSource> brdf_signal;

  /// The input of a backend with entry `entry`: ParameterError naming the backend and the
  /// missing input when this preparation did not include what the entry declares.
  TransferInput input(const CompressorEntry& entry) const;
};

/// The union of `needs`.
BackendInputs union_of(std::span<const BackendInputs> needs);
/// "T", "T, SH order 5, mesh, BTFs", ...
std::string describe(const BackendInputs& needs);

PreparedScene prepare_scene(const SceneDesc& desc, const BackendInputs& needs, StageCache& cache,
                            const PrepareOptions& options = {});
/// For registered backends by name (unknown names: ParameterError listing the registered).
PreparedScene prepare_scene_for(const SceneDesc& desc, std::span<const std::string> backends,
                                StageCache& cache, const PrepareOptions& options = {});

}  // namespace prt
