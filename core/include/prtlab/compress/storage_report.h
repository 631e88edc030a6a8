#pragma once
// What a compressed representation stores, component by component: the numbers the reports
// compare (transfers and materials alike).
#include <cstdint>
#include <string>
#include <vector>

namespace prt {

/// One stored component: name, bytes, and its byte layout in words ("u16 column id per term").
struct StorageComponent {
  std::string name;
  std::uint64_t bytes = 0;
  std::string layout;
};
struct StorageReport {
  std::vector<StorageComponent> components;
  std::uint64_t total_bytes() const;
};

}  // namespace prt
