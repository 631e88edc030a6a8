#pragma once
// The OpenCL counterpart of to_pixel_basis (transfer/radiance_to_bins.h) for SH local radiance:
// the frame loop of a backend relighting into SH converts its relighter's output buffer to the
// bins on the device (kernels/radiance_to_bins.cl), and shades from the result.
#include <cstddef>
#include <memory>

#include "prtlab/sphere/hemisphere_grid.h"

namespace cl {
class Buffer;
}

namespace prt {

class ClContext;

class DeviceRadianceToBins {
 public:
  /// For `vertices` blocks of `sh_count` = order^2 coefficients on `grid`.
  DeviceRadianceToBins(ClContext& context, const HemisphereGrid& grid, int sh_count,
                       std::size_t vertices);
  ~DeviceRadianceToBins();
  DeviceRadianceToBins(DeviceRadianceToBins&&) noexcept;
  DeviceRadianceToBins& operator=(DeviceRadianceToBins&&) noexcept;

  /// Converts `sh` (vertices x order^2 packed RGB floats) into output_buffer() (vertices x M);
  /// returns the kernel milliseconds.
  double run(const cl::Buffer& sh);
  const cl::Buffer& output_buffer() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace prt
