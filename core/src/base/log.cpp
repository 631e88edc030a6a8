#include "prtlab/base/log.h"

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>

namespace prt {
namespace {

LogLevel initial_level() {
  const char* env = std::getenv("PRTLAB_LOG");
  if (!env) return LogLevel::kInfo;
  const std::string v = env;
  if (v == "debug") return LogLevel::kDebug;
  if (v == "warn") return LogLevel::kWarn;
  if (v == "error") return LogLevel::kError;
  if (v == "silent") return LogLevel::kSilent;
  return LogLevel::kInfo;
}

std::atomic<int> g_level{static_cast<int>(initial_level())};
std::atomic<int> g_warnings{0};
std::mutex g_mutex;

}  // namespace

void set_log_level(LogLevel level) {
  g_level = static_cast<int>(level);
}
LogLevel log_level() {
  return static_cast<LogLevel>(g_level.load());
}
int warning_count() {
  return g_warnings.load();
}

void log_message(LogLevel level, std::string_view message) {
  if (level == LogLevel::kWarn) ++g_warnings;
  if (static_cast<int>(level) < g_level.load()) return;
  static constexpr const char* kPrefix[] = {"debug: ", "", "warning: ", "error: ", ""};
  std::lock_guard lock(g_mutex);
  std::fprintf(stderr, "prtlab: %s%.*s\n", kPrefix[static_cast<int>(level)],
               static_cast<int>(message.size()), message.data());
}

}  // namespace prt
