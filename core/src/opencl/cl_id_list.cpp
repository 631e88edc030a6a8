#include "prtlab/opencl/cl_id_list.h"

#include "prtlab/opencl/cl_buffer.h"

namespace prt {

void DeviceIdList::assign(ClContext& ctx, std::span<const std::uint32_t> ids) {
  count_ = ids.size();
  if (ids.empty()) return;
  if (ids.size_bytes() > capacity_bytes_) {
    capacity_bytes_ = ids.size_bytes();
    buffer_ = make_buffer(ctx, capacity_bytes_, CL_MEM_READ_ONLY, what_);
  }
  write_buffer(ctx, buffer_, ids.data(), ids.size_bytes(), what_);
}

}  // namespace prt
