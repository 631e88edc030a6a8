#include "prtlab/storage/stage_cache.h"

#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/base/named_warning.h"
#include "prtlab/storage/atomic_file.h"
#include "prtlab/storage/data_paths.h"

namespace prt {
namespace {

constexpr std::size_t kMaxStageChars = 64;
constexpr const char* kMetaKey = "stage_cache";

void validate_stage(std::string_view stage) {
  const bool ok_chars = std::all_of(stage.begin(), stage.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-';
  });
  if (stage.empty() || stage.size() > kMaxStageChars || stage.front() == '.' || !ok_chars)
    throw ParameterError(
        fmt::format("stage name '{}' is not valid for the cache (1 to {} "
                    "characters of a-z 0-9 . _ -, not starting with '.')",
                    stage, kMaxStageChars));
}

// One mutex per cache file, process-wide (whatever StageCache object asks): a second thread
// asking for an entry being computed waits and then hits, instead of computing it again and
// racing on the shared temporary file name "<file>.tmp.<pid>".
std::shared_ptr<std::mutex> entry_lock(const std::filesystem::path& file) {
  static std::mutex registry_mutex;
  static std::map<std::string, std::weak_ptr<std::mutex>> registry;
  const std::lock_guard guard(registry_mutex);
  if (registry.size() > 4096)
    std::erase_if(registry, [](const auto& e) { return e.second.expired(); });
  std::weak_ptr<std::mutex>& slot = registry[file.string()];
  std::shared_ptr<std::mutex> lock = slot.lock();
  if (!lock) {
    lock = std::make_shared<std::mutex>();
    slot = lock;
  }
  return lock;
}

}  // namespace

StageCache::StageCache() : StageCache(cache_dir()) {}
StageCache::StageCache(std::filesystem::path root) : root_(std::move(root)) {}

std::filesystem::path StageCache::path_for(std::string_view stage, const Hash128& key) const {
  validate_stage(stage);
  return root_ / std::string(stage) / (key.hex() + ".prt");
}

bool StageCache::contains(std::string_view stage, const Hash128& key) const {
  std::error_code ec;
  return std::filesystem::is_regular_file(path_for(stage, key), ec);
}

StageCache::Stats StageCache::stats() const {
  return Stats{hits_.load(), misses_.load(), corrupt_.load(), write_failures_.load()};
}

void StageCache::fetch(std::string_view stage, const Hash128& key, const Compute& compute,
                       const Consume& consume, CacheMode mode) {
  const std::filesystem::path file = path_for(stage, key);
  // Also on hits: a process that only reads still clears what a killed writer left.
  if (mode != CacheMode::kOff) remove_stale_temporaries_once(file.parent_path());
  const std::shared_ptr<std::mutex> lock = entry_lock(file);
  const std::lock_guard guard(*lock);
  if (mode == CacheMode::kUse && contains(stage, key)) {
    try {
      const ArchiveReader reader = ArchiveReader::open(file);
      // The file name is the key; the metadata repeats it, which catches files copied or
      // renamed into the wrong place.
      const auto it = reader.meta().find(kMetaKey);
      if (it == reader.meta().end() || !it->is_object() || it->value("key", "") != key.hex() ||
          it->value("stage", "") != stage)
        throw InputError(file, "its stage/key metadata does not match its name");
      consume(reader);
      ++hits_;
      // What computing it warned, said again: a cached result is never quieter.
      if (const auto w = it->find("warnings"); w != it->end() && w->is_array())
        for (const auto& e : *w)
          if (e.is_object())
            log_named_warning(e.value("name", std::string("cached")),
                              e.value("message", std::string()) + " (from the stage cache)");
      log_debug("stage '{}': cache hit {}", stage, file.string());
      return;
    } catch (const InputError& e) {
      ++corrupt_;
      log_warn("stage '{}': ignoring unusable cache entry ({}); recomputing", stage, e.what());
    }
  }

  ++misses_;
  log_debug("stage '{}': computing ({})", stage,
            mode == CacheMode::kOff ? "cache off" : file.string());
  const std::size_t mark = named_warning_mark();
  ArchiveWriter writer = compute();
  nlohmann::json warnings = nlohmann::json::array();
  for (const NamedWarning& w : named_warnings_since(mark))
    warnings.push_back({{"name", w.name}, {"message", w.message}});
  nlohmann::json meta = {{"stage", stage}, {"key", key.hex()}};
  if (!warnings.empty()) meta["warnings"] = std::move(warnings);
  writer.add_meta(kMetaKey, std::move(meta));
  bool stored = false;
  if (mode != CacheMode::kOff) {
    try {
      writer.write(file);
      stored = true;
    } catch (const Error& e) {
      ++write_failures_;
      log_warn("stage '{}': cannot store the result in the cache ({}); continuing without it",
               stage, e.what());
    }
  }
  // Reading back what was stored (rather than keeping the computed value) is what makes a miss
  // return exactly what later hits will; an error here is a bug in the stage, so it propagates.
  if (stored) {
    consume(ArchiveReader::open(file));
    return;
  }
  const std::vector<std::byte> bytes = writer.to_bytes();
  consume(ArchiveReader::from_bytes(bytes, file));
}

}  // namespace prt
