#include "prtlab/base/error.h"

namespace prt {

void check_failed(const char* expr, const char* file, int line, const std::string& msg) {
  throw Error(fmt::format("internal check failed: {} ({}:{}){}{}", expr, file, line,
                          msg.empty() ? "" : ": ", msg));
}

}  // namespace prt
