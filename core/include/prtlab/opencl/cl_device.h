#pragma once
// Choosing the OpenCL device (pattern 7 of STYLE.md).
//
// Order: the CLI's --device string, else $PRTLAB_DEVICE, else the first GPU, else PoCL's CPU
// device, else the first device. A device string is one of
//   "" / "auto" / "default"   the default order above
//   "gpu" / "cpu"             the first device of that type
//   "pocl"                    the first PoCL device
//   "P:D"                     platform index P, device index D, as listed by `clinfo -l`
//   anything else             a case-insensitive substring of the device name, device vendor,
//                             platform name or platform vendor ("nvidia", "epyc", "intel")
// A string that matches nothing falls back to the default order with a warning, unless the
// selection is strict (--device-strict, or $PRTLAB_DEVICE_STRICT=1): then it is an error, as is
// the absence of any OpenCL device. Without strict mode and without any OpenCL platform,
// select_device() warns once per process ("no OpenCL platform") and returns nullopt: callers
// then run their C++ reference paths.
//
// Before its first platform query prtlab sets PoCL defaults the user has not set (see
// apply_pocl_env_defaults and docs/opencl.md).
#include <cstddef>
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "prtlab/opencl/cl_include.h"

namespace prt {

/// What a result records about the device it ran on (provenance) and what selection matches.
struct DeviceInfo {
  int platform_index = -1;              ///< index in clGetPlatformIDs order (as `clinfo -l`)
  int device_index = -1;                ///< index within the platform
  std::string platform_name;            ///< CL_PLATFORM_NAME, "Portable Computing Language"
  std::string platform_vendor;          ///< CL_PLATFORM_VENDOR, "The pocl project"
  std::string platform_version;         ///< CL_PLATFORM_VERSION, "OpenCL 3.0 PoCL 3.1+debian ..."
  std::string device_name;              ///< CL_DEVICE_NAME, "pthread-haswell-AMD EPYC 7B13"
  std::string vendor;                   ///< CL_DEVICE_VENDOR
  std::string driver_version;           ///< CL_DRIVER_VERSION (part of every program-cache key)
  std::string opencl_version;           ///< CL_DEVICE_VERSION, "OpenCL 3.0 PoCL HSTR: ..."
  std::string opencl_c_version;         ///< CL_DEVICE_OPENCL_C_VERSION
  unsigned compute_units = 0;           ///< CL_DEVICE_MAX_COMPUTE_UNITS (PoCL: CPU threads)
  std::uint64_t global_mem_bytes = 0;   ///< CL_DEVICE_GLOBAL_MEM_SIZE
  std::uint64_t max_alloc_bytes = 0;    ///< CL_DEVICE_MAX_MEM_ALLOC_SIZE (largest one buffer)
  std::uint64_t local_mem_bytes = 0;    ///< CL_DEVICE_LOCAL_MEM_SIZE
  std::size_t max_work_group_size = 0;  ///< CL_DEVICE_MAX_WORK_GROUP_SIZE
  bool is_gpu = false;
  bool is_cpu = false;

  /// PoCL (any device type): matched on the platform name, vendor and version.
  bool is_pocl() const;
  /// One line: "0:0 pthread-haswell-AMD EPYC 7B13 [Portable Computing Language, CPU]".
  std::string label() const;
};

/// Provenance record: every field above, plus "label".
void to_json(nlohmann::json& j, const DeviceInfo& info);

/// What the user asked for.
struct DeviceRequest {
  std::string spec;     ///< device string (grammar above); empty = default order
  bool strict = false;  ///< refuse to fall back

  /// spec = cli_spec if non-empty, else $PRTLAB_DEVICE; strict = strict_flag or
  /// $PRTLAB_DEVICE_STRICT is "1"/"true"/"yes"/"on".
  static DeviceRequest resolve(std::string_view cli_spec = {}, bool strict_flag = false);
};

/// The selection rule alone, over a device list (testable without OpenCL): the index of the
/// chosen device; nullopt when `devices` is empty and the request is not strict. Warns
/// (log_warn) when it falls back; throws ParameterError (listing the devices) in strict mode
/// when nothing matches or there is no device.
std::optional<std::size_t> choose_device(std::span<const DeviceInfo> devices,
                                         const DeviceRequest& request);

/// A device with the handles needed to make a context.
struct ClDevice {
  cl::Platform platform;
  cl::Device device;
  DeviceInfo info;
};

/// Every available device of every platform, in `clinfo -l` order; empty when there is no
/// platform (no warning). Applies the PoCL defaults first.
std::vector<ClDevice> list_devices();

/// The requested device (see the rules at the top of this file). Returns nullopt, after one
/// "no OpenCL platform" warning per process, when there is no device and the request is not
/// strict.
std::optional<ClDevice> select_device(const DeviceRequest& request = DeviceRequest::resolve());

/// Sets, unless the user already set them: POCL_AFFINITY=1 (pins PoCL's worker threads; removes
/// most slow outliers) and POCL_CACHE_DIR=<prt::cache_dir()>/opencl/pocl (PoCL's kernel cache
/// lives beside prtlab's own program cache, so PRTLAB_CACHE controls both). PoCL reads them when
/// the platform is first queried, so this runs once, before prtlab's first query; it is only
/// effective if nothing in the process queried OpenCL platforms earlier.
void apply_pocl_env_defaults();

}  // namespace prt
