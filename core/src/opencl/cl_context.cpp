#include "prtlab/opencl/cl_context.h"

#include <cstdio>
#include <cstdlib>
#include <string_view>

#include "prtlab/opencl/cl_error.h"
#include "prtlab/base/log.h"

namespace prt {
namespace {

bool profile_requested() {
  const char* v = std::getenv("PRTLAB_OPENCL_PROFILE");
  if (!v) return false;
  const std::string_view s = v;
  return s == "1" || s == "on" || s == "true" || s == "yes";
}

}  // namespace

struct ClContext::Impl {
  ClDevice device;
  cl::Context context;
  cl::CommandQueue queue;
  KernelTimer timer;
  ProgramCache programs;
  bool print_profile = profile_requested();

  Impl(ClDevice dev, cl::Context ctx, cl::CommandQueue q, std::filesystem::path cache_dir)
      : device(std::move(dev)),
        context(std::move(ctx)),
        queue(std::move(q)),
        programs(context, device.device, device.info, std::move(cache_dir)) {}

  ~Impl() {
    if (!print_profile) return;
    try {
      const std::string table =
          timer.summary(fmt::format("OpenCL kernel profile, {}", device.info.label()));
      if (!table.empty()) std::fprintf(stderr, "%s", table.c_str());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "prtlab: OpenCL profile unavailable: %s\n", e.what());
    }
  }
};

std::optional<ClContext> ClContext::open(const DeviceRequest& request) {
  std::optional<ClDevice> device = select_device(request);
  if (!device) return std::nullopt;
  return ClContext(std::move(*device));
}

ClContext::ClContext(ClDevice device, std::filesystem::path program_cache_dir) {
  const std::string name = device.info.device_name;
  try {
    cl::Context context(device.device);
    cl::CommandQueue queue(context, device.device, CL_QUEUE_PROFILING_ENABLE);
    impl_ = std::make_unique<Impl>(std::move(device), std::move(context), std::move(queue),
                                   std::move(program_cache_dir));
  } catch (const cl::Error& e) {
    throw_cl_error(e, name, "creating a context and command queue");
  }
}

ClContext::~ClContext() = default;
ClContext::ClContext(ClContext&&) noexcept = default;
ClContext& ClContext::operator=(ClContext&&) noexcept = default;

const cl::Context& ClContext::context() const {
  return impl_->context;
}
const cl::Device& ClContext::device() const {
  return impl_->device.device;
}
cl::CommandQueue& ClContext::queue() {
  return impl_->queue;
}
const DeviceInfo& ClContext::info() const {
  return impl_->device.info;
}
KernelTimer& ClContext::timer() {
  return impl_->timer;
}
ProgramCache& ClContext::programs() {
  return impl_->programs;
}

void ClContext::finish() {
  try {
    impl_->queue.finish();
  } catch (const cl::Error& e) {
    throw_cl_error(e, info().device_name, "waiting for the command queue");
  }
}

void ClContext::set_print_profile_on_exit(bool on) {
  impl_->print_profile = on;
}

ClContext* default_context() {
  // Its destructor is registered when its construction completes, which is after the driver
  // was loaded by the first platform query, so it runs before the driver's own teardown.
  static std::optional<ClContext> instance = ClContext::open();
  return instance ? &*instance : nullptr;
}

}  // namespace prt
