// Fuzz target: the UBO measured-BTF reader (ubo_btf.h: DFMF, FMF, BDI). The input is the file.
// It is read twice: at the import's default resolution, where a header's texel count decides
// what is allocated and must be checked against the file first, and box-filtered to one texel,
// which decodes every measured tile. Both onto 2 x 2 view and light grids, so that a valid
// input stays fast.
#include <cstddef>
#include <cstdint>
#include <span>

#include "fuzz_support.h"
#include "prtlab/btf/ubo_btf.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static prt::fuzz::InputFile file(".btf");
  const auto& path = file.write(std::span(data, size));
  for (const int resolution : {0, 1})
    prt::fuzz::run([&] {
      prt::MeasuredImportOptions o;
      o.view_side = 2;
      o.light_side = 2;
      o.resolution = resolution;
      (void)prt::read_ubo_btf(path, o);
    });
  return 0;
}
