#include "prtlab/storage/atomic_file.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <fstream>
#include <mutex>
#include <set>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/base/log.h"

namespace prt {
namespace {

// Temporaries being written, in fixed storage a signal handler can read: unlink() is
// async-signal-safe, a std::set is not. A slot is claimed with a compare-exchange and its path
// published before `state` turns to kReady.
constexpr int kSlots = 64;
constexpr std::size_t kPathBytes = 4096;
enum SlotState : int { kFree = 0, kClaimed = 1, kReady = 2 };
struct InFlight {
  std::atomic<int> state{kFree};
  char path[kPathBytes]{};
};
std::array<InFlight, kSlots> g_in_flight;

int claim_slot(const std::filesystem::path& tmp) {
  const std::string s = tmp.string();
  if (s.size() + 1 > kPathBytes) return -1;
  for (int i = 0; i < kSlots; ++i) {
    int expected = kFree;
    if (g_in_flight[i].state.compare_exchange_strong(expected, kClaimed)) {
      std::memcpy(g_in_flight[i].path, s.c_str(), s.size() + 1);
      g_in_flight[i].state.store(kReady);
      return i;
    }
  }
  return -1;  // more than kSlots writes at once: this one is cleaned up by the stale sweep only
}

void release_slot(int i) {
  if (i >= 0) g_in_flight[i].state.store(kFree);
}

extern "C" void unlink_in_flight_and_die(int sig) {
  for (auto& slot : g_in_flight)
    if (slot.state.load() == kReady) ::unlink(slot.path);
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

bool process_is_gone(long pid) {
  if (pid <= 0) return false;
  if (pid == static_cast<long>(::getpid())) return false;
  return ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

}  // namespace

const std::string& atomic_temporary_host() {
  static const std::string tag = [] {
    std::array<char, 256> buf{};
    std::string h = ::gethostname(buf.data(), buf.size() - 1) == 0 ? buf.data() : "";
    for (char& c : h)
      if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-'))
        c = '_';
    return h.empty() ? std::string("localhost") : h;
  }();
  return tag;
}

bool is_atomic_temporary_name(const std::string& filename, long* pid, std::string* host) {
  const auto at = filename.rfind(".tmp.");
  if (at == std::string::npos || at == 0) return false;
  // "<host>.<pid>.<n>", or "<pid>.<n>" as versions before the host was named wrote.
  const std::string rest = filename.substr(at + 5);
  std::vector<std::string> parts;
  for (std::size_t from = 0;;) {
    const auto dot = rest.find('.', from);
    parts.push_back(rest.substr(from, dot == std::string::npos ? std::string::npos : dot - from));
    if (dot == std::string::npos) break;
    from = dot + 1;
  }
  if (parts.size() != 2 && parts.size() != 3) return false;
  const auto number = [](const std::string& t, auto* out) {
    if (t.empty()) return false;
    const auto r = std::from_chars(t.data(), t.data() + t.size(), *out);
    return r.ec == std::errc{} && r.ptr == t.data() + t.size();
  };
  long parsed = 0;
  unsigned long long n = 0;
  const std::size_t p = parts.size() - 2;
  if (!number(parts[p], &parsed) || !number(parts[p + 1], &n)) return false;
  std::string h;
  if (parts.size() == 3) {
    h = parts[0];
    if (h.empty() || !std::all_of(h.begin(), h.end(), [](char c) {
          return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                 c == '-' || c == '_';
        }))
      return false;
  }
  if (pid) *pid = parsed;
  if (host) *host = h;
  return true;
}

std::size_t remove_stale_temporaries(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::size_t removed = 0;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    long pid = 0;
    std::string host;
    if (!is_atomic_temporary_name(name, &pid, &host)) continue;
    // Another node's process table is not ours: its temporaries are its own to sweep.
    if (!host.empty() && host != atomic_temporary_host()) continue;
    if (!process_is_gone(pid)) continue;
    std::error_code rm;
    if (fs::remove(it->path(), rm)) {
      ++removed;
      log_debug("removed {}, left by process {} that no longer runs", it->path().string(), pid);
    }
  }
  return removed;
}

void remove_stale_temporaries_once(const std::filesystem::path& dir) {
  static std::mutex mutex;
  static std::set<std::string> swept;
  {
    const std::lock_guard guard(mutex);
    if (!swept.insert(dir.lexically_normal().string()).second) return;
  }
  if (const std::size_t n = remove_stale_temporaries(dir))
    log_info("removed {} unfinished file(s) of stopped processes in {}", n, dir.string());
}

void remove_temporaries_on_signal() {
  static std::atomic<bool> installed{false};
  if (installed.exchange(true)) return;
  for (int sig : {SIGINT, SIGTERM}) {
    struct sigaction old {};
    ::sigaction(sig, nullptr, &old);
    // A caller that ignores the signal (nohup) keeps ignoring it.
    if (old.sa_handler == SIG_IGN) continue;
    struct sigaction sa {};
    sa.sa_handler = unlink_in_flight_and_die;
    sigemptyset(&sa.sa_mask);
    ::sigaction(sig, &sa, nullptr);
  }
}

void write_files_atomically(std::span<const PendingFile> files) {
  namespace fs = std::filesystem;
  // pid + a process-wide counter: two threads writing the same path never share a temporary.
  static std::atomic<std::uint64_t> counter{0};
  std::vector<fs::path> tmps;
  std::vector<int> slots;
  auto discard = [&](std::size_t from) {
    for (std::size_t i = from; i < tmps.size(); ++i) {
      std::error_code ignored;
      fs::remove(tmps[i], ignored);
    }
    for (int slot : slots) release_slot(slot);
  };
  try {
    for (const PendingFile& f : files) {
      if (f.path.has_parent_path()) {
        std::error_code ec;
        fs::create_directories(f.path.parent_path(), ec);
        if (ec) throw InputError(f.path, fmt::format("cannot create directory: {}", ec.message()));
      }
      remove_stale_temporaries_once(f.path.has_parent_path() ? f.path.parent_path()
                                                             : fs::path("."));
      fs::path tmp = f.path;
      tmp +=
          fmt::format(".tmp.{}.{}.{}", atomic_temporary_host(), ::getpid(), counter.fetch_add(1));
      tmps.push_back(tmp);
      slots.push_back(claim_slot(tmp));
      f.write(tmp);
    }
  } catch (...) {
    discard(0);
    throw;
  }
  for (std::size_t i = 0; i < files.size(); ++i) {
    std::error_code ec;
    fs::rename(tmps[i], files[i].path, ec);
    if (ec) {
      discard(i);
      throw InputError(files[i].path,
                       fmt::format("cannot move the finished file into place: {}", ec.message()));
    }
  }
  for (int slot : slots) release_slot(slot);
}

void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(const std::filesystem::path& tmp)>& write) {
  const PendingFile file{path, write};
  write_files_atomically(std::span(&file, 1));
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
