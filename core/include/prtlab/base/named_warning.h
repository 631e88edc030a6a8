#pragma once
// Warnings with a stable name ("radiance-range", "latlong-aspect"), printed as
// "warning: [name] ..." and counted per name: the stability harness and the tests report which
// failure modes a run detected by name, not by parsing text. Also the exception for a
// computation that left its valid range.
#include <fmt/format.h>

#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "prtlab/base/error.h"

namespace prt {

void log_named_warning(std::string_view name, std::string_view message);
/// How many warnings named `name` this process has issued.
int warning_count(std::string_view name);
/// Every named warning issued so far, with its count.
std::map<std::string, int> named_warning_counts();

struct NamedWarning {
  std::string name;
  std::string message;
};
/// How many named warnings this process has issued: a mark for named_warnings_since().
std::size_t named_warning_mark();
/// The named warnings issued after `mark` (by any thread), in order. The stage cache stores
/// those of a computation with its result and issues them again on a cache hit, so that a cached
/// result is never quieter than a computed one.
std::vector<NamedWarning> named_warnings_since(std::size_t mark);

template <typename... Args>
void log_warn_named(std::string_view name, fmt::format_string<Args...> f, Args&&... args) {
  log_named_warning(name, fmt::format(f, std::forward<Args>(args)...));
}

/// A computation left its valid range on valid-looking input: a relight that overflowed float,
/// a measured error above the bound the backend declares. Raised instead of reporting the
/// number, because a table must never hold a quietly wrong value.
class NumericalError : public Error {
 public:
  using Error::Error;
};

}  // namespace prt
