// Fuzz target: the mesh loaders (mesh_io.h). The first input byte picks the format and the
// entry point, the rest is the file: OFF (prtlab's own reader), OBJ (prtlab's pre-scan, then
// assimp), PLY and STL (assimp), and load_mesh_groups by material and by object. Every load
// also runs validation, smooth normals and tangents, as a scene build would.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "fuzz_support.h"
#include "prtlab/geometry/mesh_io.h"

namespace {

struct Mode {
  const char* extension;
  bool groups;
  prt::MeshGroupKey key;
};

// Order is part of the seed format (prtlab-fuzz-seeds writes the selector byte): append only.
constexpr std::array<Mode, 7> kModes = {{
    {".off", false, prt::MeshGroupKey::kMaterial},
    {".obj", false, prt::MeshGroupKey::kMaterial},
    {".ply", false, prt::MeshGroupKey::kMaterial},
    {".stl", false, prt::MeshGroupKey::kMaterial},
    {".obj", true, prt::MeshGroupKey::kMaterial},
    {".obj", true, prt::MeshGroupKey::kObject},
    {".ply", true, prt::MeshGroupKey::kObject},
}};

// One file per extension: assimp picks its importer from the name.
prt::fuzz::InputFile& input_file(std::string_view extension) {
  static prt::fuzz::InputFile off(".off"), obj(".obj"), ply(".ply"), stl(".stl");
  if (extension == ".off") return off;
  if (extension == ".obj") return obj;
  if (extension == ".ply") return ply;
  return stl;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const Mode& mode = kModes[data[0] % kModes.size()];
  prt::fuzz::InputFile& file = input_file(mode.extension);
  return prt::fuzz::run([&] {
    const auto& path = file.write(std::span(data + 1, size - 1));
    if (mode.groups) {
      (void)prt::load_mesh_groups(path, mode.key);
    } else {
      (void)prt::load_mesh(path);
    }
  });
}
