#include "prtlab/storage/index_section.h"

#include <fmt/format.h>

#include <algorithm>

#include "prtlab/base/error.h"
#include "prtlab/storage/archive.h"

namespace prt {

std::size_t index_bytes(std::uint64_t count) {
  return count <= 256 ? 1 : (count <= 65536 ? 2 : 4);
}

void add_index_section(ArchiveWriter& archive, std::string name, std::span<const std::uint32_t> ids,
                       std::uint64_t count) {
  switch (index_bytes(count)) {
    case 1:
      archive.add_section(std::move(name), std::vector<std::uint8_t>(ids.begin(), ids.end()));
      break;
    case 2:
      archive.add_section(std::move(name), std::vector<std::uint16_t>(ids.begin(), ids.end()));
      break;
    default:
      archive.add_section(std::move(name), std::vector<std::uint32_t>(ids.begin(), ids.end()));
      break;
  }
}

std::vector<std::uint32_t> read_index_section(const ArchiveReader& archive, const std::string& name,
                                              std::uint64_t n, std::uint64_t count) {
  std::vector<std::uint32_t> ids;
  switch (index_bytes(count)) {
    case 1: {
      const auto v = archive.view<std::uint8_t>(name, n);
      ids.assign(v.begin(), v.end());
      break;
    }
    case 2: {
      const auto v = archive.view<std::uint16_t>(name, n);
      ids.assign(v.begin(), v.end());
      break;
    }
    default:
      ids = archive.section<std::uint32_t>(name, n);
      break;
  }
  const auto bad =
      std::find_if(ids.begin(), ids.end(), [&](std::uint32_t id) { return id >= count; });
  if (bad != ids.end())
    throw InputError(archive.path(),
                     fmt::format("section '{}': index {} at position {} is out of range (below {})",
                                 name, *bad, bad - ids.begin(), count));
  return ids;
}

}  // namespace prt
