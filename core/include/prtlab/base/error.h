#pragma once
// Errors at prtlab's boundaries (files, parameters, devices) are exceptions that name the
// component, the file and, where one exists, a fix. Internal invariants use PRT_CHECK (always
// on) or PRT_DCHECK (debug builds only).
#include <fmt/format.h>

#include <filesystem>
#include <stdexcept>
#include <string>

namespace prt {

/// Base of every prtlab exception. what() is a complete, user-facing sentence.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Bad user input: a file that is missing, malformed or out of range. Always names the file.
class InputError : public Error {
 public:
  InputError(const std::filesystem::path& file, const std::string& problem)
      : Error(fmt::format("{}: {}", file.string(), problem)), file_(file) {}
  const std::filesystem::path& file() const { return file_; }

 private:
  std::filesystem::path file_;
};

/// Bad parameter (command-line option, scene key, backend parameter).
class ParameterError : public Error {
 public:
  using Error::Error;
};

[[noreturn]] void check_failed(const char* expr, const char* file, int line,
                               const std::string& msg);

}  // namespace prt

#define PRT_CHECK(cond, ...)                                                                 \
  do {                                                                                       \
    if (!(cond)) ::prt::check_failed(#cond, __FILE__, __LINE__, ::fmt::format(__VA_ARGS__)); \
  } while (0)

#ifdef NDEBUG
#define PRT_DCHECK(cond, ...) \
  do {                        \
  } while (0)
#else
#define PRT_DCHECK(cond, ...) PRT_CHECK(cond, __VA_ARGS__)
#endif
