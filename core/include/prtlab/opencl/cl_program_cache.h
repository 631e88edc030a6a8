#pragma once
// Built OpenCL programs, cached twice (the Boost.Compute / VexCL pattern):
//   - in the process: one cl::Program per (source, options) for the owning context's device;
//   - on disk: the device binary under <dir>/<key>.clbin, key = XXH3-128 of (file format
//     version, source, options, platform name and version, device name, driver version).
//     The driver version is in the key because a binary from an older driver is the classic
//     stale-cache failure. A file that fails its own checks (magic, key, size, checksum) or
//     that the driver rejects is deleted and the program is rebuilt from source.
// The disk directory is <prt::cache_dir()>/opencl (so $PRTLAB_CACHE moves it);
// $PRTLAB_OPENCL_CACHE=0 turns the disk cache off. A ProgramCache belongs to one ClContext
// (programs are bound to a context); build through build_program() (cl_program.h).
#include <cstdint>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

#include "prtlab/opencl/cl_device.h"
#include "prtlab/opencl/cl_include.h"
#include "prtlab/storage/content_hash.h"

namespace prt {

/// Where programs came from, for tests and diagnostics. Counts since the cache was made.
struct ProgramCacheStats {
  int source_builds = 0;      ///< compiled from source (clBuildProgram on text)
  int binary_loads = 0;       ///< loaded from a disk binary
  int memory_hits = 0;        ///< returned from the in-process map
  int binaries_rejected = 0;  ///< disk files found unusable (then rebuilt from source)
  int binaries_written = 0;   ///< disk files written
};

class ProgramCache {
 public:
  /// disk_dir empty: no disk cache.
  ProgramCache(cl::Context context, cl::Device device, DeviceInfo info,
               std::filesystem::path disk_dir);

  /// <prt::cache_dir()>/opencl, or empty when $PRTLAB_OPENCL_CACHE is 0/off/false/no.
  static std::filesystem::path default_disk_dir();

  /// The program for `source` (complete: defines and prelude included) built with `options`.
  /// `label` names it in messages. Throws ClBuildError (with the build log, the device and the
  /// options) when the source does not compile.
  cl::Program get(std::string_view label, const std::string& source, const std::string& options);

  /// The cache key of a program; its disk file is disk_path(key).
  Hash128 key(std::string_view source, std::string_view options) const;
  std::filesystem::path disk_path(const Hash128& key) const;
  const std::filesystem::path& disk_dir() const { return disk_dir_; }

  /// Forgets the in-process programs (the disk cache stays): the next get() behaves as in a
  /// new process.
  void clear_memory();
  ProgramCacheStats stats() const;

 private:
  cl::Program build_from_source(std::string_view label, const std::string& source,
                                const std::string& options);
  std::optional<cl::Program> load_binary(std::string_view label, const Hash128& key,
                                         const std::string& options);
  void store_binary(std::string_view label, const Hash128& key, const cl::Program& program);

  cl::Context context_;
  cl::Device device_;
  DeviceInfo info_;
  std::filesystem::path disk_dir_;
  mutable std::mutex mutex_;
  std::map<Hash128, cl::Program> programs_;
  ProgramCacheStats stats_;
  bool write_warned_ = false;
};

}  // namespace prt
