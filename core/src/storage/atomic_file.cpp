#include "prtlab/storage/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <fstream>

#include "prtlab/base/error.h"

namespace prt {

void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(const std::filesystem::path& tmp)>& write) {
  namespace fs = std::filesystem;
  if (path.has_parent_path()) {
    std::error_code ec;
    fs::create_directories(path.parent_path(), ec);
    if (ec) throw InputError(path, fmt::format("cannot create directory: {}", ec.message()));
  }
  // pid + a process-wide counter: two threads writing the same path never share a temporary.
  static std::atomic<std::uint64_t> counter{0};
  fs::path tmp = path;
  tmp += fmt::format(".tmp.{}.{}", ::getpid(), counter.fetch_add(1));
  try {
    write(tmp);
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec)
      throw InputError(path,
                       fmt::format("cannot move the finished file into place: {}", ec.message()));
  } catch (...) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw;
  }
}

void write_bytes_atomically(const std::filesystem::path& path, std::span<const std::byte> bytes) {
  write_file_atomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(tmp, "cannot open for writing");
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) throw InputError(path, "write failed (disk full?)");
  });
}

void write_text_atomically(const std::filesystem::path& path, std::string_view text) {
  write_bytes_atomically(path, std::as_bytes(std::span(text.data(), text.size())));
}

}  // namespace prt
