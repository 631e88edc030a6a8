#include "prtlab/base/named_warning.h"

#include <mutex>

#include "prtlab/base/log.h"

namespace prt {
namespace {

std::mutex g_mutex;
std::map<std::string, int, std::less<>>& counts() {
  static std::map<std::string, int, std::less<>> c;
  return c;
}

// Every named warning in order; the messages are short and a run issues a handful.
std::vector<NamedWarning>& issued() {
  static std::vector<NamedWarning> w;
  return w;
}

}  // namespace

void log_named_warning(std::string_view name, std::string_view message) {
  {
    const std::lock_guard lock(g_mutex);
    auto it = counts().find(name);
    if (it == counts().end()) it = counts().emplace(std::string(name), 0).first;
    ++it->second;
    issued().push_back({std::string(name), std::string(message)});
  }
  log_message(LogLevel::kWarn, fmt::format("[{}] {}", name, message));
}

int warning_count(std::string_view name) {
  const std::lock_guard lock(g_mutex);
  const auto it = counts().find(name);
  return it == counts().end() ? 0 : it->second;
}

std::map<std::string, int> named_warning_counts() {
  const std::lock_guard lock(g_mutex);
  return {counts().begin(), counts().end()};
}

std::size_t named_warning_mark() {
  const std::lock_guard lock(g_mutex);
  return issued().size();
}

std::vector<NamedWarning> named_warnings_since(std::size_t mark) {
  const std::lock_guard lock(g_mutex);
  if (mark >= issued().size()) return {};
  return {issued().begin() + static_cast<std::ptrdiff_t>(mark), issued().end()};
}

}  // namespace prt
