// Fuzz target: the scene-file parser (scene.h). The input is the TOML file; parse_scene
// validates it without building meshes (building would load data files and resample).
#include <cstddef>
#include <cstdint>
#include <span>

#include "fuzz_support.h"
#include "prtlab/geometry/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static prt::fuzz::InputFile file(".toml");
  return prt::fuzz::run([&] { (void)prt::parse_scene(file.write(std::span(data, size))); });
}
