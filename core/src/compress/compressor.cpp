#include "prtlab/compress/compressor.h"

#include <fmt/format.h>

#include "prtlab/base/error.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt {

void check_transfer_shape(const TransferInput& input, std::string_view backend) {
  const TransferMatrix& t = input.transfer;
  if (t.cols() != static_cast<std::size_t>(input.cubemap.pixel_count()) ||
      t.local_count() != input.grid.cell_count())
    throw ParameterError(fmt::format(
        "{}: the transfer is {} x {} per vertex but the bases give M = {}, N = {}", backend,
        t.local_count(), t.cols(), input.grid.cell_count(), input.cubemap.pixel_count()));
}

void check_pixel_light(const LightCoeffs& light, std::size_t pixels, std::string_view backend) {
  if (light.basis != "pixel" || light.values.size() != pixels)
    throw ParameterError(fmt::format(
        "{}: relight needs a pixel-basis light of N = {} values, got basis '{}' with {}", backend,
        pixels, light.basis, light.values.size()));
}

}  // namespace prt
