#pragma once
// What haar's tests share: compress a transfer with the backend, and read its stored terms as
// the format defines them (independently of the relight's decoding).
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include "haar/haar.h"
#include "prtlab/compress/compressor_registry.h"
#include "prtlab/numeric/float16.h"

namespace prt::haar::test_support {

using Params = std::map<std::string, std::string>;

inline std::unique_ptr<CompressedTransfer> compress(const TransferMatrix& t, const Params& p) {
  const CubemapLayout cubemap(static_cast<int>(std::lround(std::sqrt(t.cols() / 6.0))));
  const HemisphereGrid grid(static_cast<int>(std::lround(std::sqrt(t.local_count()))));
  return CompressorRegistry::instance()
      .create(std::string(kName), p)
      ->compress({t, nullptr, cubemap, grid}, Progress::null());
}

inline const HaarArrays& arrays(const CompressedTransfer& ct) {
  return dynamic_cast<const HaarTransfer&>(ct).arrays();
}

/// Term i's stored value as the format defines it, in double.
inline double stored_value(const HaarArrays& a, std::size_t row, std::size_t i) {
  switch (a.format) {
    case ValueFormat::kFloat32:
      return a.values32[i];
    case ValueFormat::kFloat16:
      return half_to_float(a.values16[i]);
    case ValueFormat::kS8:
      return a.codes[i] * static_cast<double>(a.row_scales[row]);
  }
  return 0;
}

inline std::uint32_t stored_index(const HaarArrays& a, std::size_t i) {
  return a.wide ? a.indices32[i] : a.indices16[i];
}

}  // namespace prt::haar::test_support
