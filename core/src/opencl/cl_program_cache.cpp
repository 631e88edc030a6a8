#include "prtlab/opencl/cl_program_cache.h"

#include <fmt/format.h>

#include <array>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <vector>

#include "prtlab/base/log.h"
#include "prtlab/base/statistics.h"
#include "prtlab/opencl/cl_error.h"
#include "prtlab/storage/atomic_file.h"
#include "prtlab/storage/data_paths.h"

namespace prt {
namespace fs = std::filesystem;
namespace {

// Bump when the file layout or what goes into the key changes.
constexpr std::uint32_t kFormatVersion = 1;
constexpr std::array<char, 8> kMagic = {'P', 'R', 'T', 'C', 'L', 'B', 'I', 'N'};
// magic, version u32, reserved u32, key 16, payload size u64, payload checksum 16.
constexpr std::size_t kHeaderBytes = 8 + 4 + 4 + 16 + 8 + 16;

template <typename T>
void put(std::vector<std::byte>& out, const T& value) {
  const auto* p = reinterpret_cast<const std::byte*>(&value);
  out.insert(out.end(), p, p + sizeof(T));
}

template <typename T>
T get_at(std::span<const std::byte> in, std::size_t offset) {
  T value;
  std::memcpy(&value, in.data() + offset, sizeof(T));
  return value;
}

std::optional<std::vector<std::byte>> read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return std::nullopt;
  const std::streamsize size = in.tellg();
  if (size < 0) return std::nullopt;
  std::vector<std::byte> bytes(static_cast<std::size_t>(size));
  in.seekg(0);
  if (!in.read(reinterpret_cast<char*>(bytes.data()), size)) return std::nullopt;
  return bytes;
}

// Why a cache file cannot be used, or empty when its framing is intact; payload receives the
// device binary.
std::string check_file(std::span<const std::byte> file, const Hash128& key,
                       std::span<const std::byte>& payload) {
  if (file.size() < kHeaderBytes) return fmt::format("truncated ({} bytes)", file.size());
  if (std::memcmp(file.data(), kMagic.data(), kMagic.size()) != 0)
    return "not a prtlab program binary";
  if (get_at<std::uint32_t>(file, 8) != kFormatVersion) return "written by another prtlab version";
  std::array<std::byte, 16> stored_key;
  std::memcpy(stored_key.data(), file.data() + 16, 16);
  if (Hash128::from_canonical_bytes(stored_key) != key) return "its key does not match its name";
  const auto size = get_at<std::uint64_t>(file, 32);
  if (size != file.size() - kHeaderBytes)
    return fmt::format("size mismatch ({} bytes recorded, {} present)", size,
                       file.size() - kHeaderBytes);
  payload = file.subspan(kHeaderBytes);
  std::array<std::byte, 16> stored_sum;
  std::memcpy(stored_sum.data(), file.data() + 40, 16);
  if (Hash128::from_canonical_bytes(stored_sum) != hash_bytes(payload)) return "checksum mismatch";
  return {};
}

}  // namespace

ProgramCache::ProgramCache(cl::Context context, cl::Device device, DeviceInfo info,
                           fs::path disk_dir)
    : context_(std::move(context)),
      device_(std::move(device)),
      info_(std::move(info)),
      disk_dir_(std::move(disk_dir)) {}

fs::path ProgramCache::default_disk_dir() {
  if (const char* v = std::getenv("PRTLAB_OPENCL_CACHE")) {
    const std::string s = v;
    if (s == "0" || s == "off" || s == "false" || s == "no") return {};
  }
  return cache_dir() / "opencl";
}

Hash128 ProgramCache::key(std::string_view source, std::string_view options) const {
  Hasher h;
  h.add("prtlab OpenCL program").add(kFormatVersion);
  h.add(source).add(options);
  h.add(info_.platform_name).add(info_.platform_version);
  h.add(info_.device_name).add(info_.driver_version);
  return h.digest();
}

fs::path ProgramCache::disk_path(const Hash128& key) const {
  return disk_dir_.empty() ? fs::path() : disk_dir_ / (key.hex() + ".clbin");
}

cl::Program ProgramCache::get(std::string_view label, const std::string& source,
                              const std::string& options) {
  const Hash128 k = key(source, options);
  std::lock_guard lock(mutex_);
  if (auto it = programs_.find(k); it != programs_.end()) {
    ++stats_.memory_hits;
    return it->second;
  }
  std::optional<cl::Program> program = load_binary(label, k, options);
  if (!program) {
    program = build_from_source(label, source, options);
    store_binary(label, k, *program);
  }
  programs_.emplace(k, *program);
  return *program;
}

cl::Program ProgramCache::build_from_source(std::string_view label, const std::string& source,
                                            const std::string& options) {
  const auto t0 = std::chrono::steady_clock::now();
  cl::Program program;
  try {
    program = cl::Program(context_, source);
    program.build({device_}, options.c_str());
  } catch (const cl::Error& e) {
    std::string log;
    try {
      if (program()) log = program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(device_);
    } catch (const cl::Error&) {
      log = "(the driver returned no build log)";
    }
    while (!log.empty() && (log.back() == '\0' || log.back() == '\n')) log.pop_back();
    throw ClBuildError(
        e.err(),
        fmt::format("OpenCL program '{}' failed to build on device {} ({}, driver {}) with "
                    "options '{}': {} returned {}; build log (line numbers refer to the .cl "
                    "files):\n{}",
                    label, info_.device_name, info_.platform_name, info_.driver_version, options,
                    e.what(), cl_error_name(e.err()), log.empty() ? "(empty)" : log),
        log);
  }
  ++stats_.source_builds;
  log_debug("OpenCL: built '{}' from source in {:.0f} ms on {}", label, ms_since(t0),
            info_.device_name);
  return program;
}

std::optional<cl::Program> ProgramCache::load_binary(std::string_view label, const Hash128& key,
                                                     const std::string& options) {
  if (disk_dir_.empty()) return std::nullopt;
  const fs::path path = disk_path(key);
  std::error_code ec;
  if (!fs::exists(path, ec)) return std::nullopt;
  const auto t0 = std::chrono::steady_clock::now();
  std::string problem;
  std::optional<cl::Program> program;
  if (auto file = read_file(path); !file) {
    problem = "unreadable";
  } else {
    std::span<const std::byte> payload;
    problem = check_file(*file, key, payload);
    if (problem.empty()) {
      try {
        const auto* p = reinterpret_cast<const unsigned char*>(payload.data());
        cl::Program::Binaries binaries{std::vector<unsigned char>(p, p + payload.size())};
        std::vector<cl_int> status;
        cl::Program loaded(context_, {device_}, binaries, &status);
        loaded.build({device_}, options.c_str());
        program = std::move(loaded);
      } catch (const cl::Error& e) {
        problem =
            fmt::format("the driver rejected it: {} returned {}", e.what(), cl_error_name(e.err()));
      }
    }
  }
  if (!program) {
    ++stats_.binaries_rejected;
    log_warn("OpenCL program cache: {} ('{}') is unusable ({}); rebuilding from source",
             path.string(), label, problem);
    fs::remove(path, ec);
    return std::nullopt;
  }
  ++stats_.binary_loads;
  log_debug("OpenCL: loaded '{}' from {} in {:.0f} ms", label, path.string(), ms_since(t0));
  return program;
}

void ProgramCache::store_binary(std::string_view label, const Hash128& key,
                                const cl::Program& program) {
  if (disk_dir_.empty()) return;
  try {
    const auto binaries = program.getInfo<CL_PROGRAM_BINARIES>();
    if (binaries.size() != 1 || binaries[0].empty()) return;  // driver offers no binary
    const auto payload = std::as_bytes(std::span(binaries[0]));
    std::vector<std::byte> file;
    file.reserve(kHeaderBytes + payload.size());
    file.insert(file.end(), reinterpret_cast<const std::byte*>(kMagic.data()),
                reinterpret_cast<const std::byte*>(kMagic.data()) + kMagic.size());
    put(file, kFormatVersion);
    put(file, std::uint32_t{0});
    const auto key_bytes = key.canonical_bytes();
    file.insert(file.end(), key_bytes.begin(), key_bytes.end());
    put(file, static_cast<std::uint64_t>(payload.size()));
    const auto sum = hash_bytes(payload).canonical_bytes();
    file.insert(file.end(), sum.begin(), sum.end());
    file.insert(file.end(), payload.begin(), payload.end());
    write_bytes_atomically(disk_path(key), file);
    ++stats_.binaries_written;
  } catch (const std::exception& e) {
    // A read-only or full cache directory must not stop the run; it only costs build time.
    if (!write_warned_)
      log_warn(
          "OpenCL program cache: cannot store '{}' under {} ({}); programs will be "
          "rebuilt in every process",
          label, disk_dir_.string(), e.what());
    write_warned_ = true;
  }
}

void ProgramCache::clear_memory() {
  std::lock_guard lock(mutex_);
  programs_.clear();
}

ProgramCacheStats ProgramCache::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

}  // namespace prt
