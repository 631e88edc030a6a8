#pragma once
// Runs a reader that must refuse its input in a child process and reports whether it threw an
// InputError without its peak memory passing a limit: a file declaring a huge size must fail
// before anything of that size is allocated (the parent's own memory does not count, and an
// allocation that succeeds cannot leak into the test's address space).
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <functional>

#include "prtlab/base/error.h"

namespace prt::testing {

/// Success when every call of `read` in a forked child throws an InputError and the child's
/// peak RSS stays at or below `max_megabytes`.
inline ::testing::AssertionResult refused_within_memory(const std::function<void()>& read,
                                                        long max_megabytes) {
  const pid_t child = ::fork();
  if (child < 0) return ::testing::AssertionFailure() << "fork failed";
  if (child == 0) {
    int code = 0;
    try {
      read();
      code = 2;
    } catch (const InputError&) {
    } catch (...) {
      code = 3;
    }
    rusage usage{};
    ::getrusage(RUSAGE_SELF, &usage);
    if (code == 0 && usage.ru_maxrss > max_megabytes * 1024) code = 4;  // ru_maxrss is in KB
    ::_exit(code);
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  if (!WIFEXITED(status)) return ::testing::AssertionFailure() << "the reader crashed";
  switch (WEXITSTATUS(status)) {
    case 0:
      return ::testing::AssertionSuccess();
    case 2:
      return ::testing::AssertionFailure() << "the input was read, not refused";
    case 3:
      return ::testing::AssertionFailure() << "refused with another exception than InputError";
    case 4:
      return ::testing::AssertionFailure() << "peak RSS above " << max_megabytes << " MB";
  }
  return ::testing::AssertionFailure() << "exit status " << WEXITSTATUS(status);
}

}  // namespace prt::testing
