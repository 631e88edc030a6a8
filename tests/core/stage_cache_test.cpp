// The stage cache: a miss computes and stores, a hit loads without computing, an unusable
// cached file is reported and recomputed (never used), refresh/off modes, unwritable caches.
#include "prtlab/storage/stage_cache.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <bit>
#include <chrono>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include "prtlab/base/log.h"
#include "prtlab/base/named_warning.h"
#include "prtlab/storage/atomic_file.h"

namespace prt {
namespace {

namespace fs = std::filesystem;

class StageCacheTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    root_ = fs::temp_directory_path() /
            fmt::format("prtlab_stage_cache_test_{}_{}", ::getpid(), info->name());
    fs::remove_all(root_);
    saved_level_ = log_level();
    set_log_level(LogLevel::kError);  // the warnings are expected; they are counted below
  }
  void TearDown() override {
    set_log_level(saved_level_);
    std::error_code ec;
    fs::remove_all(root_, ec);
  }

  // A stand-in stage: its result is a vector derived from `seed`; `computed` counts calls.
  StageCache::Compute compute(int seed) {
    return [this, seed] {
      ++computed_;
      std::vector<float> v(64);
      for (std::size_t i = 0; i < v.size(); ++i) v[i] = static_cast<float>(seed) + 0.125f * i;
      v[7] = std::bit_cast<float>(0x7fc00000u + static_cast<std::uint32_t>(seed));  // a NaN payload
      ArchiveWriter w("test-stage", 1);
      w.add_meta("seed", seed);
      w.add_section("values", std::move(v));
      return w;
    };
  }
  static std::vector<float> load(const ArchiveReader& r) {
    r.expect_kind("test-stage", 1);
    return r.section<float>("values", 64);
  }
  static std::vector<float> expected(int seed) {
    std::vector<float> v(64);
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = static_cast<float>(seed) + 0.125f * i;
    v[7] = std::bit_cast<float>(0x7fc00000u + static_cast<std::uint32_t>(seed));
    return v;
  }
  static bool bit_equal(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
  }
  static Hash128 key(int k) { return Hasher().add("test-stage").add(1).add(k).digest(); }

  void corrupt_byte(const fs::path& file, std::uint64_t offset) {
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(static_cast<std::streamoff>(offset));
    char c = 0;
    f.read(&c, 1);
    c = static_cast<char>(c ^ 0x40);
    f.seekp(static_cast<std::streamoff>(offset));
    f.write(&c, 1);
  }

  fs::path root_;
  int computed_ = 0;
  LogLevel saved_level_ = LogLevel::kInfo;
};

TEST_F(StageCacheTest, PathLayoutAndStageNames) {
  const StageCache cache(root_);
  const Hash128 k = key(1);
  EXPECT_EQ(cache.path_for("transfer", k), root_ / "transfer" / (k.hex() + ".prt"));
  EXPECT_EQ(cache.path_for("sh-transfer.v2_x", k).parent_path().filename(), "sh-transfer.v2_x");
  for (const char* bad : {"", "..", ".hidden", "a/b", "../escape", "Transfer", "x y", "é"})
    EXPECT_THROW((void)cache.path_for(bad, k), ParameterError) << "'" << bad << "'";
  EXPECT_THROW((void)cache.path_for(std::string(65, 'a'), k), ParameterError);
  EXPECT_FALSE(cache.contains("transfer", k));
}

TEST_F(StageCacheTest, DefaultRootIsPrtlabCache) {
  const char* old = std::getenv("PRTLAB_CACHE");
  const std::string saved = old ? old : "";
  ::setenv("PRTLAB_CACHE", root_.c_str(), 1);
  const StageCache cache;
  EXPECT_EQ(cache.root(), root_);
  if (old)
    ::setenv("PRTLAB_CACHE", saved.c_str(), 1);
  else
    ::unsetenv("PRTLAB_CACHE");
}

TEST_F(StageCacheTest, MissComputesAndStoresThenHitLoadsWithoutComputing) {
  StageCache cache(root_);
  const auto first = cache.get_or_compute("stage", key(1), compute(1), load);
  EXPECT_EQ(computed_, 1);
  EXPECT_TRUE(bit_equal(first, expected(1)));
  EXPECT_TRUE(cache.contains("stage", key(1)));
  // Stored atomically: the stage directory holds the entry and nothing else.
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(root_ / "stage")) files.push_back(e.path());
  EXPECT_EQ(files, std::vector<fs::path>{cache.path_for("stage", key(1))});
  // The stored archive names its stage and key.
  const ArchiveReader stored = ArchiveReader::open(cache.path_for("stage", key(1)));
  EXPECT_EQ(stored.meta().at("stage_cache").at("key"), key(1).hex());

  const auto second = cache.get_or_compute("stage", key(1), compute(1), load);
  EXPECT_EQ(computed_, 1) << "a hit must not compute";
  EXPECT_TRUE(bit_equal(second, first));
  // A fresh cache object (a new process) hits as well.
  StageCache again(root_);
  (void)again.get_or_compute("stage", key(1), compute(1), load);
  EXPECT_EQ(computed_, 1);
  EXPECT_EQ(cache.stats().hits, 1);
  EXPECT_EQ(cache.stats().misses, 1);
  EXPECT_EQ(cache.stats().corrupt, 0);
}

TEST_F(StageCacheTest, DifferentKeysAndStagesDoNotCollide) {
  StageCache cache(root_);
  for (int k = 0; k < 5; ++k)
    EXPECT_TRUE(bit_equal(cache.get_or_compute("stage", key(k), compute(k), load), expected(k)));
  EXPECT_TRUE(bit_equal(cache.get_or_compute("other", key(0), compute(100), load), expected(100)));
  EXPECT_EQ(computed_, 6);
  // Every entry still holds its own value.
  for (int k = 0; k < 5; ++k)
    EXPECT_TRUE(bit_equal(cache.get_or_compute("stage", key(k), compute(-1), load), expected(k)));
  EXPECT_EQ(computed_, 6);
}

TEST_F(StageCacheTest, CorruptOrForeignCachedFilesAreRecomputedWithAWarning) {
  StageCache cache(root_);
  const fs::path file = cache.path_for("stage", key(1));
  (void)cache.get_or_compute("stage", key(1), compute(1), load);
  const auto size = fs::file_size(file);
  const std::vector<std::function<void()>> damages = {
      [&] { corrupt_byte(file, size / 2); },                              // bit rot in the payload
      [&] { fs::resize_file(file, size - 20); },                          // truncated
      [&] { std::ofstream(file, std::ios::trunc) << "not an archive"; },  // foreign file
      [&] {  // a valid archive of another key, copied into this key's place
        fs::remove(file);
        (void)cache.get_or_compute("stage", key(2), compute(2), load);
        fs::copy_file(cache.path_for("stage", key(2)), file);
      },
      [&] {  // a valid archive of another kind (the load refuses it)
        ArchiveWriter w("other-kind", 1);
        w.add_meta("stage_cache", {{"stage", "stage"}, {"key", key(1).hex()}});
        w.write(file);
      },
  };
  for (std::size_t i = 0; i < damages.size(); ++i) {
    damages[i]();
    const int computed_before = computed_;
    const int warnings_before = warning_count();
    const auto v = cache.get_or_compute("stage", key(1), compute(1), load);
    EXPECT_TRUE(bit_equal(v, expected(1))) << "damage " << i;
    EXPECT_EQ(computed_, computed_before + 1) << "damage " << i;
    EXPECT_EQ(warning_count(), warnings_before + 1) << "damage " << i;
    // The entry was repaired: the next call hits.
    (void)cache.get_or_compute("stage", key(1), compute(1), load);
    EXPECT_EQ(computed_, computed_before + 1) << "damage " << i;
  }
  EXPECT_EQ(cache.stats().corrupt, static_cast<int>(damages.size()));
}

TEST_F(StageCacheTest, RefreshRecomputesAndOffNeverTouchesTheCache) {
  StageCache cache(root_);
  (void)cache.get_or_compute("stage", key(1), compute(1), load);
  // Refresh: computes even though present, and the new result replaces the old.
  const auto refreshed =
      cache.get_or_compute("stage", key(1), compute(2), load, CacheMode::kRefresh);
  EXPECT_EQ(computed_, 2);
  EXPECT_TRUE(bit_equal(refreshed, expected(2)));
  EXPECT_TRUE(bit_equal(cache.get_or_compute("stage", key(1), compute(3), load), expected(2)));
  EXPECT_EQ(computed_, 2);
  // Off: computes, does not read the cached entry, writes nothing.
  const auto off = cache.get_or_compute("stage", key(1), compute(4), load, CacheMode::kOff);
  EXPECT_TRUE(bit_equal(off, expected(4)));
  const auto off_new = cache.get_or_compute("stage", key(9), compute(9), load, CacheMode::kOff);
  EXPECT_TRUE(bit_equal(off_new, expected(9)));
  EXPECT_EQ(computed_, 4);
  EXPECT_FALSE(cache.contains("stage", key(9)));
  EXPECT_TRUE(bit_equal(cache.get_or_compute("stage", key(1), compute(5), load), expected(2)));
}

TEST_F(StageCacheTest, ConcurrentRequestsForOneEntryComputeItOnce) {
  std::atomic<int> calls{0};
  const StageCache::Compute slow = [&] {
    ++calls;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));  // widen the race window
    ArchiveWriter w("test-stage", 1);
    w.add_section("values", expected(3));
    return w;
  };
  StageCache a(root_), b(root_);  // two cache objects: the lock is per file, not per object
  std::vector<std::vector<float>> results(4);
  std::vector<std::thread> threads;
  for (std::size_t i = 0; i < results.size(); ++i)
    threads.emplace_back(
        [&, i] { results[i] = (i % 2 ? a : b).get_or_compute("stage", key(3), slow, load); });
  for (auto& t : threads) t.join();
  EXPECT_EQ(calls.load(), 1);
  for (const auto& r : results) EXPECT_TRUE(bit_equal(r, expected(3)));
  EXPECT_EQ(a.stats().hits + b.stats().hits, 3);
}

TEST_F(StageCacheTest, UnwritableCacheStillReturnsTheResult) {
  fs::create_directories(root_);
  std::ofstream(root_ / "file") << "x";
  StageCache cache(root_ / "file");  // the root is a regular file: nothing can be stored
  const int warnings_before = warning_count();
  const auto v = cache.get_or_compute("stage", key(1), compute(1), load);
  EXPECT_TRUE(bit_equal(v, expected(1)));
  EXPECT_EQ(warning_count(), warnings_before + 1);
  EXPECT_EQ(cache.stats().write_failures, 1);
}

TEST_F(StageCacheTest, ErrorsOfAFreshComputationPropagate) {
  StageCache cache(root_);
  const StageCache::Compute failing = []() -> ArchiveWriter {
    throw ParameterError("bad parameter");
  };
  EXPECT_THROW((void)cache.get_or_compute("stage", key(1), failing, load), ParameterError);
  EXPECT_FALSE(cache.contains("stage", key(1)));
  // A load that refuses what compute just produced is a bug in the stage, not a cache problem.
  const auto wrong_load = [](const ArchiveReader& r) { return r.section<double>("values"); };
  EXPECT_THROW((void)cache.get_or_compute("stage", key(2), compute(2), wrong_load), InputError);
}

// A process id that ran and has exited (and been reaped): nothing runs under it now.
long dead_pid() {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  int status = 0;
  ::waitpid(child, &status, 0);
  return static_cast<long>(child);
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  return {std::istreambuf_iterator<char>(in), {}};
}

void touch(const fs::path& p) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << "half an archive";
}

// A warning of the computation is stored with its result and issued again on every hit: a
// cached result must not be quieter than a computed one.
TEST_F(StageCacheTest, AComputationsNamedWarningsAreIssuedAgainOnAHit) {
  StageCache cache(root_);
  const auto warning = [this] {
    log_named_warning("test-stage-warning", "the fit was regularised");
    return compute(1)();
  };
  const int before = warning_count("test-stage-warning");
  (void)cache.get_or_compute("stage", key(1), warning, load);
  EXPECT_EQ(warning_count("test-stage-warning"), before + 1);
  const std::size_t mark = named_warning_mark();
  (void)cache.get_or_compute("stage", key(1), warning, load);
  EXPECT_EQ(computed_, 1) << "the second call is a hit";
  EXPECT_EQ(warning_count("test-stage-warning"), before + 2);
  const auto again = named_warnings_since(mark);
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(again[0].name, "test-stage-warning");
  EXPECT_NE(again[0].message.find("the fit was regularised (from the stage cache)"),
            std::string::npos)
      << again[0].message;
  // A computation that warned nothing stays quiet on a hit.
  (void)cache.get_or_compute("stage", key(2), compute(2), load);
  const std::size_t quiet = named_warning_mark();
  (void)cache.get_or_compute("stage", key(2), compute(2), load);
  EXPECT_TRUE(named_warnings_since(quiet).empty());
}

TEST_F(StageCacheTest, TemporariesOfKilledProcessesAreRemovedOnFirstUse) {
  StageCache cache(root_);
  const fs::path dir = cache.path_for("stage", key(1)).parent_path();
  const long gone = dead_pid();
  const fs::path stale = dir / fmt::format("0123abcd.prt.tmp.{}.0", gone);
  const fs::path live = dir / fmt::format("4567abcd.prt.tmp.{}.3", static_cast<long>(::getppid()));
  const fs::path other = dir / "notes.tmp.txt";  // not a name prtlab makes
  // The same dead pid on this host (as prtlab names it now) and on another node of a cluster
  // sharing the folder: only this host's is ours to judge.
  const fs::path stale_here =
      dir / fmt::format("89abcdef.prt.tmp.{}.{}.1", atomic_temporary_host(), gone);
  const fs::path other_node =
      dir / fmt::format("fedcba98.prt.tmp.not-{}.{}.1", atomic_temporary_host(), gone);
  touch(stale);
  touch(live);
  touch(other);
  touch(stale_here);
  touch(other_node);
  (void)cache.get_or_compute("stage", key(1), compute(1), load);
  EXPECT_FALSE(fs::exists(stale)) << "a temporary of process " << gone << " was left";
  EXPECT_FALSE(fs::exists(stale_here)) << "a temporary of process " << gone << " was left";
  EXPECT_TRUE(fs::exists(live)) << "a running process's temporary was removed";
  EXPECT_TRUE(fs::exists(other));
  EXPECT_TRUE(fs::exists(other_node)) << "another node's in-flight temporary was removed";
}

TEST(AtomicFile, TemporaryNamesAreRecognisedExactly) {
  long pid = 0;
  std::string host = "x";
  EXPECT_TRUE(is_atomic_temporary_name("a.prt.tmp.123.4", &pid, &host));
  EXPECT_EQ(pid, 123);
  EXPECT_EQ(host, "");
  EXPECT_TRUE(is_atomic_temporary_name("a.prt.tmp.node-07_a.321.4", &pid, &host));
  EXPECT_EQ(pid, 321);
  EXPECT_EQ(host, "node-07_a");
  for (const char* name :
       {"a.prt.tmp.h.x.4", "a.prt.tmp.h!.1.4", "a.prt.tmp..1.4", "a.prt.tmp.h.1.4.5"})
    EXPECT_FALSE(is_atomic_temporary_name(name)) << name;
  for (const char* name : {"a.prt", "a.prt.tmp.123", "a.prt.tmp.x.4", "a.prt.tmp.12.4x", ".tmp.1.2",
                           "a.prt.tmp..4", "a.prt.tmp.1.", "a.tmp.1.2.extra"})
    EXPECT_FALSE(is_atomic_temporary_name(name)) << name;
}

TEST(AtomicFile, AProcesssFirstWriteIntoAFolderRemovesItsStaleTemporaries) {
  const fs::path dir = fs::temp_directory_path() / fmt::format("prtlab_atomic_{}", ::getpid());
  fs::remove_all(dir);
  const long gone = dead_pid();
  const fs::path mine = dir / fmt::format("out.json.tmp.{}.7", gone);
  const fs::path others = dir / fmt::format("other.json.tmp.{}.7", gone);
  const fs::path live = dir / fmt::format("live.json.tmp.{}.7", static_cast<long>(::getppid()));
  touch(mine);
  touch(others);
  touch(live);
  write_text_atomically(dir / "out.json", "{}");
  EXPECT_FALSE(fs::exists(mine));
  EXPECT_FALSE(fs::exists(others));
  EXPECT_TRUE(fs::exists(live)) << "a running process's temporary was removed";
  EXPECT_EQ(slurp(dir / "out.json"), "{}");
  fs::remove_all(dir);
}

// SIGTERM (and SIGINT) in the middle of a write: the process still dies of the signal, and the
// temporary it was writing is gone.
TEST(AtomicFile, ATerminatedWriteLeavesNoTemporary) {
  const fs::path dir = fs::temp_directory_path() / fmt::format("prtlab_atomic_sig_{}", ::getpid());
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (int sig : {SIGTERM, SIGINT}) {
    const pid_t child = ::fork();
    if (child == 0) {
      remove_temporaries_on_signal();
      write_file_atomically(dir / "big.prt", [&](const fs::path& tmp) {
        std::ofstream(tmp) << "partial";
        ::raise(sig);
      });
      ::_exit(0);  // not reached: the signal ends the process
    }
    int status = 0;
    ::waitpid(child, &status, 0);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << "status " << status;
    std::vector<std::string> left;
    for (const auto& e : fs::directory_iterator(dir)) left.push_back(e.path().filename().string());
    EXPECT_TRUE(left.empty()) << "left behind: " << left.front();
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace prt
