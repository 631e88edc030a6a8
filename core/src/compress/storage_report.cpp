#include "prtlab/compress/storage_report.h"

#include <numeric>

namespace prt {

std::uint64_t StorageReport::total_bytes() const {
  return std::accumulate(components.begin(), components.end(), std::uint64_t{0},
                         [](std::uint64_t s, const StorageComponent& c) { return s + c.bytes; });
}

}  // namespace prt
