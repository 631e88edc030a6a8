// Fuzz target: every registered material backend's load (material_registry.h). As for
// transfers (fuzz_transfer_load.cpp): the input is a compressed-material archive with its
// envelope made valid, load_material dispatches on its "backend" metadata, seeds hold one
// archive per registered material, and a loaded material is saved again.
#include <cstddef>
#include <cstdint>
#include <span>

#include "fuzz_support.h"
#include "prtlab/compress/material_registry.h"
#include "prtlab/storage/archive.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static prt::fuzz::InputFile file(".prt");
  return prt::fuzz::run([&] {
    const auto& path = prt::fuzz::write_with_valid_envelope(file, std::span(data, size));
    const auto material = prt::load_material(path);
    (void)material->storage();
    (void)material->flops_per_pixel();
    (void)material->declared_error_bound();
    (void)material->light_basis();
    (void)material->sampling();
    prt::ArchiveWriter again("fuzz", 1);
    material->save(again);
    (void)again.to_bytes();
  });
}
