#pragma once
// The transfer stage of a scene, cached: precompute_scene_transfer() returns T (and the SH
// transfer when asked) for a scene, loading it from the stage cache when nothing it depends on
// has changed.
//
// The cache key hashes the stage's format version, the scene file's bytes, the bytes of every
// mesh file the scene reads, the SH order, and kMeshPipelineVersion. Hashing inputs rather than
// the built mesh lets a cache hit skip the mesh build (decimation takes seconds for the larger
// scenes). Whoever changes how meshes are built from the same inputs (decimation, subdivision,
// normals, frames, procedural shapes) or how T is computed must bump kMeshPipelineVersion.
#include <filesystem>

#include "prtlab/geometry/scene.h"
#include "prtlab/storage/content_hash.h"
#include "prtlab/storage/stage_cache.h"
#include "prtlab/transfer/distributed_transfer.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt {

inline constexpr std::uint32_t kMeshPipelineVersion = 2;

struct PrecomputeOptions {
  int sh_order = 0;  ///< 0: no SH transfer
  CacheMode cache = CacheMode::kUse;
  bool show_progress = true;
  /// Spread a computation over these ranks (collective then: every rank calls with the same
  /// scene); null or one rank: this process alone. The root decides hit or miss and alone
  /// reads and writes the cache.
  Communicator* comm = nullptr;
};

struct SceneTransfer {
  TransferResult result;
  Hash128 key;
  bool cache_hit = false;
  double seconds = 0;       ///< this call's wall time (load on a hit, build + compute on a miss)
  double mesh_seconds = 0;  ///< building the mesh (0 on a hit)
  std::filesystem::path cache_file;
  /// Distributed: false on the ranks other than the root, whose `result` is empty.
  bool holds_result = true;
  /// Distributed and computed: every rank's share (on the root).
  std::vector<RankTransferShare> shares;
};

/// Hash of everything the scene's mesh depends on (scene file bytes, mesh file bytes, version).
Hash128 scene_input_hash(const SceneDesc& desc);

SceneTransfer precompute_scene_transfer(const SceneDesc& desc, const PrecomputeOptions& options,
                                        StageCache& cache);

}  // namespace prt
