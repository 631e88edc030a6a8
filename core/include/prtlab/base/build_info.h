#pragma once
#include <string>

namespace prt {

/// What built this binary; every results file records it (with machine_description()).
struct BuildInfo {
  const char* version;
  const char* git_hash;  ///< short hash, "-dirty" when the tree had uncommitted changes
  const char* build_type;
  const char* compiler;
  const char* source_dir;
};
const BuildInfo& build_info();

/// "hostname, CPU model, N cores, M GiB" read from /proc; used in provenance records.
std::string machine_description();

}  // namespace prt
