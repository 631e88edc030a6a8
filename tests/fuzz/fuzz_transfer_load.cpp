// Fuzz target: every registered transfer backend's load (compressor_registry.h). The input is a
// compressed-transfer archive whose envelope is made valid (with_valid_envelope), so mutations
// reach the backend's own checks; load_compressed dispatches on its "backend" metadata, as
// `prtlab` does with a saved file. Seeds hold one archive per registered backend. A loaded
// result is saved again, which reads every part of it the archive filled.
#include <cstddef>
#include <cstdint>
#include <span>

#include "fuzz_support.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/storage/archive.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static prt::fuzz::InputFile file(".prt");
  return prt::fuzz::run([&] {
    const auto& path = prt::fuzz::write_with_valid_envelope(file, std::span(data, size));
    const auto ct = prt::load_compressed(path);
    (void)ct->storage();
    (void)ct->flops_per_relight();
    (void)ct->declared_error_bound();
    prt::ArchiveWriter again("fuzz", 1);
    ct->save(again);
    (void)again.to_bytes();
  });
}
