// Fuzz target: the EXR / environment-map loader (environment_map.h, image_io.h). The input is
// the file: load_latlong_exr reads it (OpenEXR underneath) and, for small images, resamples it
// onto a small cubemap, as `prtlab env` does with a light.
#include <cstddef>
#include <cstdint>
#include <span>

#include "fuzz_support.h"
#include "prtlab/lighting/environment_map.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static prt::fuzz::InputFile file(".exr");
  return prt::fuzz::run([&] {
    const auto& path = file.write(std::span(data, size));
    const prt::LatLongImage image = prt::load_latlong_exr(path);
    // Resampling costs in proportion to the texels; a bound keeps every input fast.
    if (static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) <= 4096)
      (void)prt::resample_to_cubemap(image, 2);
  });
}
