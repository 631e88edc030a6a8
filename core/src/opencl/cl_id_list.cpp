#include "prtlab/opencl/cl_id_list.h"

#include "prtlab/opencl/cl_buffer.h"

namespace prt {

void DeviceIdList::assign(ClContext& ctx, std::span<const std::uint32_t> ids) {
  // The count changes last: a failed allocation or write leaves the previous list usable.
  if (ids.size_bytes() > capacity_bytes_) {
    buffer_ = make_buffer(ctx, ids.size_bytes(), CL_MEM_READ_ONLY, what_);
    capacity_bytes_ = ids.size_bytes();
    count_ = 0;
  }
  if (!ids.empty()) write_buffer(ctx, buffer_, ids.data(), ids.size_bytes(), what_);
  count_ = ids.size();
}

}  // namespace prt
