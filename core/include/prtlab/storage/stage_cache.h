#pragma once
// The stage cache: each pipeline stage (visibility, transfer matrix, compressed transfer, ...)
// stores its artifact as a prtlab archive under a key that hashes everything the artifact
// depends on, so that re-running an experiment recomputes only what changed.
//
//   <root>/<stage>/<32 hex digits of the key>.prt        root = prt::cache_dir() ($PRTLAB_CACHE)
//
// The key is the caller's business: hash the stage's kind version, its parameters and the
// content hashes of its inputs with a Hasher. The cache adds nothing to the key.
//
// Guarantees:
//   - a hit never calls compute; a miss calls it once and stores the result atomically;
//   - the value returned on a miss is loaded from the stored archive, exactly as a later hit
//     would load it, so hits and misses give bit-identical results;
//   - a cached file that cannot be used (corrupt, truncated, another kind, a newer version,
//     a load that throws InputError, a key that does not match its name) is reported with a
//     warning and recomputed, never used;
//   - if the cache cannot be written (read-only, disk full), the stage still returns its
//     result (with a warning) from memory.
// Thread-safe: threads asking for the same entry are serialised (the second one hits), other
// entries proceed in parallel. Two processes computing the same key at once both succeed; the
// last rename wins.
#include <atomic>
#include <filesystem>
#include <functional>
#include <optional>
#include <string_view>
#include <type_traits>
#include <utility>

#include "prtlab/storage/archive.h"
#include "prtlab/storage/content_hash.h"

namespace prt {

enum class CacheMode {
  kUse,      ///< load on a hit, compute and store on a miss
  kRefresh,  ///< always compute and store (the --force of the CLI)
  kOff,      ///< always compute, neither read nor write the cache
};

class StageCache {
 public:
  /// Rooted at prt::cache_dir().
  StageCache();
  explicit StageCache(std::filesystem::path root);

  const std::filesystem::path& root() const { return root_; }

  /// <root>/<stage>/<key hex>.prt. stage: 1..64 characters of [a-z0-9._-], not starting with
  /// '.' (ParameterError otherwise), so that it is always one safe directory name.
  std::filesystem::path path_for(std::string_view stage, const Hash128& key) const;
  /// A file exists for the key (not verified: get_or_compute verifies).
  bool contains(std::string_view stage, const Hash128& key) const;

  using Compute = std::function<ArchiveWriter()>;
  using Consume = std::function<void(const ArchiveReader&)>;

  /// The core: hands a verified archive for (stage, key) to consume, computing and storing it
  /// first when needed. An InputError thrown by consume on a cached file counts as a corrupt
  /// entry (warning, recompute); on a freshly computed one it propagates.
  void fetch(std::string_view stage, const Hash128& key, const Compute& compute,
             const Consume& consume, CacheMode mode = CacheMode::kUse);

  /// The typical use: load(reader) -> T turns the archive into the stage's result.
  ///   auto t = cache.get_or_compute("transfer", key,
  ///                                 [&] { return save_transfer(compute_transfer(...)); },
  ///                                 [](const ArchiveReader& r) { return load_transfer(r); });
  template <typename Load>
  auto get_or_compute(std::string_view stage, const Hash128& key, const Compute& compute,
                      Load&& load, CacheMode mode = CacheMode::kUse)
      -> std::invoke_result_t<Load&, const ArchiveReader&> {
    using T = std::invoke_result_t<Load&, const ArchiveReader&>;
    std::optional<T> result;
    fetch(
        stage, key, compute,
        [&](const ArchiveReader& reader) { result.emplace(std::invoke(load, reader)); }, mode);
    return std::move(*result);
  }

  /// Counters since construction (for reports and tests).
  struct Stats {
    int hits = 0;
    int misses = 0;          ///< computed because absent, refreshed, or cache off
    int corrupt = 0;         ///< cached files found unusable and recomputed
    int write_failures = 0;  ///< results that could not be stored
  };
  Stats stats() const;

 private:
  std::filesystem::path root_;
  std::atomic<int> hits_{0}, misses_{0}, corrupt_{0}, write_failures_{0};
};

}  // namespace prt
