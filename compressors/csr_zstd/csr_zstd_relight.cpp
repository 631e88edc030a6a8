// The C++ relight of backend `csr_zstd`: every frame is decompressed into its thread's scratch
// buffer and multiplied at once, while it is in cache. Each row is summed as prt::relight_exact
// sums it (four accumulators over the counts, then 1/s^2), and as csr_zstd.cl does.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "csr_zstd/csr_zstd.h"
#include "prtlab/base/error.h"

namespace prt::csr_zstd {
namespace {

typedef float Float4 __attribute__((vector_size(16)));

template <typename Column>
void product_frame(const FrameView& v, const Column* columns, const Float4* light, float scale,
                   Rgb* out) {
  const std::uint8_t* counts = v.counts;
  for (std::size_t row = v.row_begin; row < v.row_end; ++row) {
    Float4 a0{}, a1{}, a2{}, a3{};
    std::uint32_t i = v.offsets[row - v.row_begin] - v.entry_begin;
    const std::uint32_t e = v.offsets[row - v.row_begin + 1] - v.entry_begin;
    for (; i + 4 <= e; i += 4) {
      a0 += static_cast<float>(counts[i + 0]) * light[columns[i + 0]];
      a1 += static_cast<float>(counts[i + 1]) * light[columns[i + 1]];
      a2 += static_cast<float>(counts[i + 2]) * light[columns[i + 2]];
      a3 += static_cast<float>(counts[i + 3]) * light[columns[i + 3]];
    }
    for (; i < e; ++i) a0 += static_cast<float>(counts[i]) * light[columns[i]];
    const Float4 sum = ((a0 + a1) + (a2 + a3)) * scale;
    out[row] = Rgb(sum[0], sum[1], sum[2]);
  }
}

}  // namespace

void CsrZstdTransfer::relight(const LightCoeffs& light, LocalRadiance& out) const {
  const FramedCsr& csr = *csr_;
  check_pixel_light(light, static_cast<std::size_t>(csr.pixel_count), kName);
  if (out.basis != RadianceBasis::kPixel || out.dim != csr.local_count ||
      out.vertices != csr.vertices || out.values.size() != csr.rows()) {
    out = LocalRadiance(RadianceBasis::kPixel, csr.local_count, csr.vertices);
  }
  std::vector<Float4> l4(light.values.size());
  for (std::size_t k = 0; k < l4.size(); ++k)
    l4[k] = Float4{light.values[k].x, light.values[k].y, light.values[k].z, 0.f};
  const float scale = static_cast<float>(csr.scale());
  Rgb* result = out.values.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, csr.frame_count(), 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t f = r.begin(); f != r.end(); ++f) {
                        const FrameView v = decoder_->decode(csr, f);
                        if (v.columns16 != nullptr) {
                          product_frame(v, v.columns16, l4.data(), scale, result);
                        } else {
                          product_frame(v, v.columns32, l4.data(), scale, result);
                        }
                      }
                    });
}

}  // namespace prt::csr_zstd
