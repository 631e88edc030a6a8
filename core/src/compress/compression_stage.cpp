#include "prtlab/compress/compression_stage.h"

#include <chrono>
#include <filesystem>

#include "prtlab/base/error.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/storage/archive.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt {

std::string compression_stage(const std::string& backend) {
  return "compressed-" + backend;
}

Hash128 compression_key(const std::string& backend,
                        const std::map<std::string, std::string>& params,
                        const Hash128& transfer_key) {
  const auto& entry = CompressorRegistry::instance().get(backend);
  Hasher h;
  h.add("compressed-transfer").add(backend).add(entry.version).add(entry.origin).add(transfer_key);
  // A plugin rebuilt in place must not reuse results of its previous build.
  if (entry.origin != "built-in" && std::filesystem::exists(entry.origin)) h.add_file(entry.origin);
  for (const auto& [k, v] : ParamSet(backend, entry.params, params).canonical()) h.add(k).add(v);
  return h.digest();
}

CompressionResult compress_cached(const std::string& backend,
                                  const std::map<std::string, std::string>& params,
                                  const TransferInput& input, const Hash128& transfer_key,
                                  StageCache& cache, CacheMode mode, bool show_progress) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto& registry = CompressorRegistry::instance();
  const auto& entry = registry.get(backend);
  const ParamSet validated(backend, entry.params, params);
  CompressionResult out;
  out.params = validated.canonical();
  out.key = compression_key(backend, params, transfer_key);

  bool computed = false;
  cache.fetch(
      compression_stage(backend), out.key,
      [&] {
        computed = true;
        auto compressor = entry.create(validated);
        Progress progress("compress " + backend, static_cast<std::int64_t>(input.transfer.rows()),
                          show_progress);
        const auto tc = std::chrono::steady_clock::now();
        auto ct = compressor->compress(input, progress);
        progress.finish();
        const double secs =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - tc).count();
        ArchiveWriter w("compressed-transfer", 1);
        w.add_meta("backend", ct->backend());
        w.add_meta("compress_seconds", secs);
        w.add_meta("params", out.params);
        ct->save(w);
        return w;
      },
      [&](const ArchiveReader& r) {
        const auto name = r.meta_value<std::string>("backend");
        if (name != backend)
          throw InputError(r.path(),
                           fmt::format("holds backend '{}', expected '{}'", name, backend));
        out.compressed = entry.load(r);
        out.compress_seconds = r.meta().value("compress_seconds", 0.0);
      },
      mode);
  out.cache_hit = !computed;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace prt
