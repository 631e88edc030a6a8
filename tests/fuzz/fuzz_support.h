#pragma once
// Shared by the fuzz targets (tests/fuzz/fuzz_*.cpp, docs/fuzzing.md).
//
// A target returns normally for every input: an exception derived from std::exception is the
// documented answer to a bad file (InputError, ParameterError, ...) and is caught by run().
// Everything else (a crash, a sanitizer report, an abort, an uncaught non-standard exception,
// a hang, an allocation above libFuzzer's -malloc_limit_mb) is a bug in the code under test.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "prtlab/base/log.h"
#include "prtlab/base/progress.h"
#include "prtlab/storage/content_hash.h"

namespace prt::fuzz {

/// Silences logging and progress once per process: a warning per input would dominate the
/// run time and bury libFuzzer's own output.
inline void quiet_once() {
  static const bool done = [] {
    set_log_level(LogLevel::kSilent);
    Progress::set_quiet(true);
    return true;
  }();
  (void)done;
}

/// Runs `body`, treating standard exceptions as the expected rejection of a bad input.
template <typename F>
int run(F&& body) {
  quiet_once();
  try {
    std::forward<F>(body)();
  } catch (const std::exception& e) {
    // A clean refusal: what a loader must do with a bad file. PRTLAB_FUZZ_VERBOSE prints it
    // (to see why a seed or a kept input is refused).
    static const bool verbose = std::getenv("PRTLAB_FUZZ_VERBOSE") != nullptr;
    if (verbose) std::fprintf(stderr, "refused: %s\n", e.what());
  }
  return 0;
}

/// One scratch file per process (and per extension), overwritten by every input, for loaders
/// that only take a path. The extension matters: loaders dispatch on it.
class InputFile {
 public:
  explicit InputFile(std::string_view extension) {
    dir_ = std::filesystem::temp_directory_path() / ("prtlab-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
    path_ = dir_ / ("input" + std::string(extension));
  }
  ~InputFile() {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  const std::filesystem::path& write(std::span<const std::uint8_t> bytes) {
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
    out.close();
    return path_;
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path dir_;
  std::filesystem::path path_;
};

/// The input with a valid archive envelope (docs/file-format.md): cut to a multiple of 16
/// bytes, the file length written at offset 16 and into the trailer, the end marker and the
/// XXH3-128 checksum recomputed. Without this almost every mutation would stop at the checksum
/// and the fuzzer would never reach the header, section and backend parsers. Inputs too short
/// for a trailer come back unchanged.
inline std::vector<std::byte> with_valid_envelope(std::span<const std::uint8_t> input) {
  constexpr std::size_t kTrailer = 32, kMin = 48 + kTrailer;
  const auto* first = reinterpret_cast<const std::byte*>(input.data());
  std::vector<std::byte> out(first, first + input.size());
  if (out.size() < kMin) return out;
  out.resize(out.size() / 16 * 16);
  const std::uint64_t length = out.size();
  const auto put_u64 = [&](std::size_t at, std::uint64_t v) {
    for (int k = 0; k < 8; ++k) out[at + static_cast<std::size_t>(k)] = std::byte(v >> (8 * k));
  };
  put_u64(16, length);
  std::memcpy(out.data() + length - kTrailer, "PRTLEND", 8);  // with its terminating zero
  put_u64(length - kTrailer + 8, length);
  const Hash128 sum = hash_bytes(std::span<const std::byte>(out.data(), length - 16));
  const auto canonical = sum.canonical_bytes();
  std::memcpy(out.data() + length - 16, canonical.data(), canonical.size());
  return out;
}

/// The input with a valid envelope, written to `file`: what the loaders of compressed
/// transfers and materials read.
inline const std::filesystem::path& write_with_valid_envelope(InputFile& file,
                                                              std::span<const std::uint8_t> input) {
  const auto fixed = with_valid_envelope(input);
  return file.write(std::span(reinterpret_cast<const std::uint8_t*>(fixed.data()), fixed.size()));
}

}  // namespace prt::fuzz
