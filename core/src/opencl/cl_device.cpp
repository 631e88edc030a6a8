#include "prtlab/opencl/cl_device.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <charconv>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>

#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/base/named_warning.h"
#include "prtlab/opencl/cl_error.h"
#include "prtlab/storage/data_paths.h"

namespace prt {
namespace {

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

bool contains_ci(std::string_view haystack, std::string_view needle) {
  return lower(haystack).find(lower(needle)) != std::string::npos;
}

bool env_truthy(const char* var) {
  const char* v = std::getenv(var);
  if (!v) return false;
  const std::string s = lower(v);
  return s == "1" || s == "true" || s == "yes" || s == "on";
}

// "P:D" with two non-negative integers.
std::optional<std::pair<int, int>> parse_index_pair(std::string_view spec) {
  const auto colon = spec.find(':');
  if (colon == std::string_view::npos) return std::nullopt;
  auto parse = [](std::string_view s) -> std::optional<int> {
    int v = 0;
    if (s.empty()) return std::nullopt;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || end != s.data() + s.size() || v < 0) return std::nullopt;
    return v;
  };
  const auto p = parse(spec.substr(0, colon));
  const auto d = parse(spec.substr(colon + 1));
  if (!p || !d) return std::nullopt;
  return std::pair{*p, *d};
}

bool matches(const DeviceInfo& d, std::string_view spec) {
  const std::string s = lower(spec);
  if (s == "gpu") return d.is_gpu;
  if (s == "cpu") return d.is_cpu;
  if (s == "pocl") return d.is_pocl();
  if (const auto pd = parse_index_pair(s))
    return d.platform_index == pd->first && d.device_index == pd->second;
  return contains_ci(d.device_name, s) || contains_ci(d.vendor, s) ||
         contains_ci(d.platform_name, s) || contains_ci(d.platform_vendor, s);
}

std::size_t default_choice(std::span<const DeviceInfo> devices) {
  for (std::size_t i = 0; i < devices.size(); ++i)
    if (devices[i].is_gpu) return i;
  for (std::size_t i = 0; i < devices.size(); ++i)
    if (devices[i].is_pocl() && devices[i].is_cpu) return i;
  return 0;
}

std::string device_list(std::span<const DeviceInfo> devices) {
  if (devices.empty()) return "none";
  std::vector<std::string> labels;
  for (const auto& d : devices) labels.push_back(d.label());
  return fmt::format("{}", fmt::join(labels, "; "));
}

bool is_default_spec(std::string_view spec) {
  const std::string s = lower(spec);
  return s.empty() || s == "auto" || s == "default";
}

DeviceInfo describe(const cl::Platform& platform, const cl::Device& device, int platform_index,
                    int device_index) {
  DeviceInfo info;
  info.platform_index = platform_index;
  info.device_index = device_index;
  info.platform_name = platform.getInfo<CL_PLATFORM_NAME>();
  info.platform_vendor = platform.getInfo<CL_PLATFORM_VENDOR>();
  info.platform_version = platform.getInfo<CL_PLATFORM_VERSION>();
  info.device_name = device.getInfo<CL_DEVICE_NAME>();
  info.vendor = device.getInfo<CL_DEVICE_VENDOR>();
  info.driver_version = device.getInfo<CL_DRIVER_VERSION>();
  info.opencl_version = device.getInfo<CL_DEVICE_VERSION>();
  info.opencl_c_version = device.getInfo<CL_DEVICE_OPENCL_C_VERSION>();
  info.compute_units = device.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>();
  info.global_mem_bytes = device.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>();
  info.max_alloc_bytes = device.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>();
  info.local_mem_bytes = device.getInfo<CL_DEVICE_LOCAL_MEM_SIZE>();
  info.max_work_group_size = device.getInfo<CL_DEVICE_MAX_WORK_GROUP_SIZE>();
  const cl_device_type type = device.getInfo<CL_DEVICE_TYPE>();
  info.is_gpu = (type & CL_DEVICE_TYPE_GPU) != 0;
  info.is_cpu = (type & CL_DEVICE_TYPE_CPU) != 0;
  // Drivers pad some strings with a trailing NUL or spaces.
  for (std::string* s :
       {&info.platform_name, &info.platform_vendor, &info.platform_version, &info.device_name,
        &info.vendor, &info.driver_version, &info.opencl_version, &info.opencl_c_version}) {
    while (!s->empty() && (s->back() == '\0' || s->back() == ' ')) s->pop_back();
  }
  return info;
}

struct Enumeration {
  std::vector<ClDevice> devices;
  std::string problem;  // why there are none (empty when the query itself succeeded)
};

Enumeration enumerate() {
  apply_pocl_env_defaults();
  Enumeration out;
  std::vector<cl::Platform> platforms;
  try {
    cl::Platform::get(&platforms);
  } catch (const cl::Error& e) {
    out.problem = fmt::format("{} returned {}", e.what(), cl_error_name(e.err()));
    return out;
  }
  for (std::size_t p = 0; p < platforms.size(); ++p) {
    std::vector<cl::Device> devices;
    try {
      platforms[p].getDevices(CL_DEVICE_TYPE_ALL, &devices);
    } catch (const cl::Error& e) {
      if (e.err() != CL_DEVICE_NOT_FOUND)
        log_warn("OpenCL platform {}: listing its devices failed ({}); skipping it", p,
                 cl_error_name(e.err()));
      continue;
    }
    for (std::size_t d = 0; d < devices.size(); ++d) {
      try {
        if (!devices[d].getInfo<CL_DEVICE_AVAILABLE>()) continue;
        out.devices.push_back(
            {platforms[p], devices[d],
             describe(platforms[p], devices[d], static_cast<int>(p), static_cast<int>(d))});
      } catch (const cl::Error& e) {
        log_warn("OpenCL device {}:{}: querying it failed ({}); skipping it", p, d,
                 cl_error_name(e.err()));
      }
    }
  }
  if (out.devices.empty() && out.problem.empty())
    out.problem = platforms.empty() ? "no platform is installed" : "the platforms list no device";
  return out;
}

}  // namespace

bool DeviceInfo::is_pocl() const {
  return contains_ci(platform_name, "portable computing language") ||
         contains_ci(platform_vendor, "pocl") || contains_ci(platform_version, "pocl");
}

std::string DeviceInfo::label() const {
  return fmt::format("{}:{} {} [{}, {}]", platform_index, device_index, device_name, platform_name,
                     is_gpu ? "GPU" : (is_cpu ? "CPU" : "other"));
}

void to_json(nlohmann::json& j, const DeviceInfo& d) {
  j = nlohmann::json{{"label", d.label()},
                     {"platform_index", d.platform_index},
                     {"device_index", d.device_index},
                     {"platform_name", d.platform_name},
                     {"platform_vendor", d.platform_vendor},
                     {"platform_version", d.platform_version},
                     {"device_name", d.device_name},
                     {"vendor", d.vendor},
                     {"driver_version", d.driver_version},
                     {"opencl_version", d.opencl_version},
                     {"opencl_c_version", d.opencl_c_version},
                     {"compute_units", d.compute_units},
                     {"global_mem_bytes", d.global_mem_bytes},
                     {"max_alloc_bytes", d.max_alloc_bytes},
                     {"local_mem_bytes", d.local_mem_bytes},
                     {"max_work_group_size", d.max_work_group_size},
                     {"is_gpu", d.is_gpu},
                     {"is_cpu", d.is_cpu},
                     {"is_pocl", d.is_pocl()}};
}

DeviceRequest DeviceRequest::resolve(std::string_view cli_spec, bool strict_flag) {
  DeviceRequest r;
  if (!cli_spec.empty()) {
    r.spec = std::string(cli_spec);
  } else if (const char* env = std::getenv("PRTLAB_DEVICE"); env && *env) {
    r.spec = env;
  }
  r.strict = strict_flag || env_truthy("PRTLAB_DEVICE_STRICT");
  return r;
}

std::optional<std::size_t> choose_device(std::span<const DeviceInfo> devices,
                                         const DeviceRequest& request) {
  if (devices.empty()) {
    if (request.strict)
      throw ParameterError(fmt::format(
          "OpenCL: no device available{} and device selection is strict "
          "(PRTLAB_DEVICE_STRICT / --device-strict); install an OpenCL driver "
          "(e.g. pocl-opencl-icd) or drop strict mode to run the C++ reference paths",
          is_default_spec(request.spec) ? "" : fmt::format(" (asked for '{}')", request.spec)));
    return std::nullopt;
  }
  if (is_default_spec(request.spec)) return default_choice(devices);
  for (std::size_t i = 0; i < devices.size(); ++i)
    if (matches(devices[i], request.spec)) return i;
  if (request.strict)
    throw ParameterError(fmt::format(
        "OpenCL: no device matches '{}' and device selection is strict; available: {} "
        "(a device string is gpu, cpu, pocl, P:D or a substring of the device or platform name)",
        request.spec, device_list(devices)));
  const std::size_t fallback = default_choice(devices);
  log_warn(
      "OpenCL: no device matches '{}' (available: {}); using {} instead "
      "(set PRTLAB_DEVICE_STRICT=1 to make this an error)",
      request.spec, device_list(devices), devices[fallback].label());
  return fallback;
}

std::vector<ClDevice> list_devices() {
  return enumerate().devices;
}

std::optional<ClDevice> select_device(const DeviceRequest& request) {
  Enumeration e = enumerate();
  std::vector<DeviceInfo> infos;
  for (const auto& d : e.devices) infos.push_back(d.info);
  if (infos.empty() && request.strict)
    throw ParameterError(fmt::format(
        "OpenCL: no device available ({}) and device selection is strict "
        "(PRTLAB_DEVICE_STRICT / --device-strict); install an OpenCL driver (e.g. pocl-opencl-icd)",
        e.problem));
  const auto index = choose_device(infos, request);
  if (!index) {
    static std::atomic<bool> warned{false};
    if (!warned.exchange(true))
      log_warn(
          "no OpenCL platform ({}); running the C++ reference paths instead "
          "(install pocl-opencl-icd for a CPU device)",
          e.problem);
    return std::nullopt;
  }
  log_debug("OpenCL device: {} (driver {})", infos[*index].label(), infos[*index].driver_version);
  return std::move(e.devices[*index]);
}

namespace {

bool writable_directory(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  return !ec && std::filesystem::is_directory(dir, ec) && ::access(dir.c_str(), W_OK | X_OK) == 0;
}

}  // namespace

void apply_pocl_env_defaults() {
  static std::once_flag once;
  std::call_once(once, [] {
    // setenv with overwrite = 0 keeps whatever the user chose.
    ::setenv("POCL_AFFINITY", "1", 0);
    if (const char* user = std::getenv("POCL_CACHE_DIR"); user && *user) return;
    // PoCL refuses to start without a writable kernel cache, and the ICD loader then reports no
    // platform at all: a read-only prtlab cache would look like a missing driver.
    namespace fs = std::filesystem;
    const fs::path wanted = cache_dir() / "opencl" / "pocl";
    fs::path use = wanted;
    if (!writable_directory(wanted)) {
      use = fs::temp_directory_path() / fmt::format("prtlab-pocl-{}", ::getuid());
      if (!writable_directory(use)) return;  // PoCL's own default, and its own error
      log_warn_named("cache-not-writable",
                     "the cache folder {} is not writable; PoCL's kernel cache uses {} instead "
                     "(set PRTLAB_CACHE or POCL_CACHE_DIR to choose)",
                     wanted.string(), use.string());
    }
    ::setenv("POCL_CACHE_DIR", use.c_str(), 0);
  });
}

}  // namespace prt

// PoCL, its LLVM and the ICD loader keep allocations until exit by design, which LeakSanitizer
// reports as thousands of leaks and a failed test under the asan preset. These suppressions
// cover only those libraries, in every binary that uses prtlab's OpenCL runtime (this object
// is linked whenever a device is selected). Weak, so that a program defining its own
// suppressions wins (it should then include these lines).
extern "C" __attribute__((weak, used)) const char* __lsan_default_suppressions() {
  return "leak:libpocl.so\n"
         "leak:libLLVM\n"
         "leak:libclang-cpp\n"
         "leak:libOpenCL.so\n";
}
