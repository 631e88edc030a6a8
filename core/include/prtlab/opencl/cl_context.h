#pragma once
// One OpenCL device ready for work: its context, an in-order command queue with profiling
// enabled (every launch is timed, cl_timer.h), the device's description for provenance, and
// the context's program cache (cl_program_cache.h). Backends receive a ClContext& in upload().
//
//   auto ctx = prt::ClContext::open(prt::DeviceRequest::resolve(cli_device));
//   if (!ctx) { /* no OpenCL: run the C++ reference path */ }
//   cl::Program p = prt::build_program(*ctx, "selftest");
#include <memory>
#include <optional>
#include <string>

#include "prtlab/opencl/cl_device.h"
#include "prtlab/opencl/cl_include.h"
#include "prtlab/opencl/cl_program_cache.h"
#include "prtlab/opencl/cl_timer.h"

namespace prt {

class ClContext {
 public:
  /// The requested device (cl_device.h), or nullopt when there is no OpenCL device and the
  /// request is not strict (after one warning per process).
  static std::optional<ClContext> open(const DeviceRequest& request = DeviceRequest::resolve());

  /// A context on `device`; programs are cached on disk under `program_cache_dir` (empty: no
  /// disk cache).
  explicit ClContext(ClDevice device,
                     std::filesystem::path program_cache_dir = ProgramCache::default_disk_dir());
  ~ClContext();
  ClContext(ClContext&&) noexcept;
  ClContext& operator=(ClContext&&) noexcept;
  ClContext(const ClContext&) = delete;
  ClContext& operator=(const ClContext&) = delete;

  const cl::Context& context() const;
  const cl::Device& device() const;
  cl::CommandQueue& queue();
  const DeviceInfo& info() const;
  KernelTimer& timer();
  ProgramCache& programs();

  /// Blocks until the queue is empty; turns a failure into a ClError.
  void finish();

  /// Print the timer's summary (stderr) when this context is destroyed; default on when
  /// $PRTLAB_OPENCL_PROFILE is 1.
  void set_print_profile_on_exit(bool on);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A process-wide context on the device DeviceRequest::resolve() picks, made on first use
/// (for tests, benchmarks and tools that need one device); nullptr without OpenCL. Destroyed
/// at exit (printing the profile summary if $PRTLAB_OPENCL_PROFILE=1).
ClContext* default_context();

}  // namespace prt
