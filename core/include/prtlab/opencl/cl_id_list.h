#pragma once
// A device list of u32 ids that a relighter replaces now and then but reads every launch: the
// vertex subset of DeviceRelighter::set_vertex_subset. The buffer grows to the largest list seen
// and is written once per list, never once per light.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "prtlab/opencl/cl_include.h"

namespace prt {

class ClContext;

class DeviceIdList {
 public:
  /// `what` names the list in error messages ("cpca vertex subset").
  explicit DeviceIdList(std::string what) : what_(std::move(what)) {}

  /// Replaces the list on `ctx`'s device (blocking write; the caller validates the ids).
  void assign(ClContext& ctx, std::span<const std::uint32_t> ids);
  std::size_t size() const { return count_; }
  bool empty() const { return count_ == 0; }
  /// At least size() ids. Allocated by the first non-empty assign(): a kernel must not be
  /// launched with it before (relighters return early on an empty subset).
  const cl::Buffer& buffer() const { return buffer_; }

 private:
  std::string what_;
  cl::Buffer buffer_;
  std::size_t count_ = 0;
  std::size_t capacity_bytes_ = 0;
};

}  // namespace prt
