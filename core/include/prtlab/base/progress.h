#pragma once
// Progress reporting for long stages. Thread-safe advance(); the terminal bar redraws at most
// ten times a second and only when stderr is a terminal (quiet otherwise, and in --quiet mode).
#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace prt {

class Progress {
 public:
  /// A progress sink that prints nothing.
  static Progress& null();

  Progress(std::string label, std::int64_t total, bool enabled = true);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void advance(std::int64_t n = 1);
  void finish();
  std::int64_t done() const { return done_.load(); }
  std::int64_t total() const { return total_; }
  /// Global switch used by --quiet.
  static void set_quiet(bool quiet);

 private:
  void redraw(bool final);
  std::string label_;
  std::int64_t total_;
  bool enabled_;
  std::atomic<std::int64_t> done_{0};
  std::chrono::steady_clock::time_point start_;
  std::atomic<std::int64_t> last_draw_ns_{0};
  std::mutex draw_mutex_;
  bool finished_ = false;
};

}  // namespace prt
