// The stored model of backend `cpca_sh` read as a pixel-basis transfer: per vertex the matrix
// X~_p rebuilt from its cluster's representatives and its weights, mapped to the bins through
// sh_matrix_model.h, for the declared Frobenius error and model_radiance() (stored_model.h).
// Neither calls the relight: it multiplies the light into each representative first and blends
// the products, this rebuilds the matrices and multiplies last.
#include <cmath>

#include "cpca_sh/cpca_sh.h"
#include "prtlab/compress/sh_matrix_model.h"

namespace prt::cpca_sh {

void vertex_matrix(const CpcaShArrays& a, std::size_t p, bool magnitude, std::span<double> x) {
  const std::size_t dim = a.signal_dim();
  const std::uint32_t c = a.ids[p], f = a.first[c];
  const double scale = a.format == WeightFormat::kS8 ? a.vertex_scales[p] : 1.0;
  const float* mean = a.reps.data() + static_cast<std::size_t>(f) * dim;
  for (std::size_t j = 0; j < dim; ++j) x[j] = magnitude ? std::abs(mean[j]) : mean[j];
  const float* w = a.weight_values.data() + a.weight_offsets[p];
  const std::uint32_t k = a.first[c + 1] - f - 1;
  for (std::uint32_t i = 0; i < k; ++i) {
    const double wi = magnitude ? std::abs(scale * w[i]) : scale * w[i];
    const float* rep = a.reps.data() + static_cast<std::size_t>(f + 1 + i) * dim;
    for (std::size_t j = 0; j < dim; ++j) x[j] += wi * (magnitude ? std::abs(rep[j]) : rep[j]);
  }
}

void declare_model_error(CpcaShArrays& a, const TransferInput& input) {
  a.local_count = input.grid.cell_count();
  a.frobenius_error =
      ShMatrixModel(input.cubemap, input.grid, a.order, a.output_order)
          .relative_frobenius_error(input.transfer, [&](std::size_t p, std::span<double> x) {
            vertex_matrix(a, p, false, x);
          });
}

ModelRadiance CpcaShTransfer::model_radiance(const Cubemap& radiance) const {
  const int side = static_cast<int>(std::lround(std::sqrt(static_cast<double>(a_.local_count))));
  const ShMatrixModel model(radiance.layout, HemisphereGrid(side), a_.order, a_.output_order);
  return model.radiance(
      radiance, a_.vertices,
      [&](std::size_t p, std::span<double> x) { vertex_matrix(a_, p, false, x); },
      [&](std::size_t p, std::span<double> x) { vertex_matrix(a_, p, true, x); });
}

}  // namespace prt::cpca_sh
