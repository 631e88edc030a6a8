#pragma once
// The compression stage, cached: a backend's CompressedTransfer for a transfer key and a set of
// parameters is stored in the stage cache ("compressed/<backend>") and loaded on the next run.
// The key hashes the transfer's key, the backend name and its canonical parameters (defaults
// included), so changing any parameter recompresses and nothing else does.
#include <map>
#include <memory>
#include <string>

#include "prtlab/compress/compressor.h"
#include "prtlab/storage/content_hash.h"
#include "prtlab/storage/stage_cache.h"

namespace prt {

struct CompressionResult {
  std::unique_ptr<CompressedTransfer> compressed;
  std::map<std::string, std::string> params;  ///< canonical, defaults included
  Hash128 key;
  bool cache_hit = false;
  double compress_seconds = 0;  ///< of the run that produced it (stored in the archive)
  double seconds = 0;           ///< this call (load on a hit)
};

/// The stage and the key compress_cached files a result under (what a collective run asks the
/// cache before it compresses).
std::string compression_stage(const std::string& backend);
Hash128 compression_key(const std::string& backend,
                        const std::map<std::string, std::string>& params,
                        const Hash128& transfer_key);

CompressionResult compress_cached(const std::string& backend,
                                  const std::map<std::string, std::string>& params,
                                  const TransferInput& input, const Hash128& transfer_key,
                                  StageCache& cache, CacheMode mode = CacheMode::kUse,
                                  bool show_progress = true);

}  // namespace prt
