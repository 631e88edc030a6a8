#pragma once
// Test scaffolding shared by every suite: a scratch folder removed on exit, and a private
// prtlab cache per test process (set before any OpenCL or stage-cache use).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace prt::testing {

/// A fresh folder under the system temp folder, named after the process, `tag` and the running
/// test (so parallel test processes never share one); removed with everything in it.
class TempDir {
 public:
  explicit TempDir(const std::string& tag = "test") {
    std::string name = "prtlab_" + tag + "_" + std::to_string(::getpid());
    if (const auto* info = ::testing::UnitTest::GetInstance()->current_test_info())
      name += std::string("_") + info->test_suite_name() + "_" + info->name();
    for (auto& c : name)
      if (c == '/') c = '_';
    path_ = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

/// Points PRTLAB_CACHE at a private folder of this process and PoCL's kernel cache at the one
/// the test processes of this build share. Call it from a namespace-scope initialiser, before
/// any OpenCL platform query; the folder is removed at exit.
inline const std::filesystem::path& use_private_cache(const std::string& tag) {
  static const std::filesystem::path root = [&] {
    const auto p = std::filesystem::temp_directory_path() /
                   ("prtlab_" + tag + "_cache_" + std::to_string(::getpid()));
    std::filesystem::create_directories(p);
    ::setenv("PRTLAB_CACHE", p.c_str(), 1);
#ifdef PRTLAB_BINARY_DIR
    ::setenv("POCL_CACHE_DIR", PRTLAB_BINARY_DIR "/test-cache/pocl", 0);
#endif
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(root, ec);
    });
    return p;
  }();
  return root;
}

}  // namespace prt::testing
