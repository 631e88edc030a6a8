// The C++ relight of backend `csr_zstd`: every frame is decompressed into its thread's scratch
// buffer and multiplied at once, while it is in cache. Each row is summed as prt::relight_exact
// sums it (four accumulators over the counts, then 1/s^2), and as csr_zstd.cl does. The vertex
// subset relight decompresses only the frames holding a listed row (frame_tasks) and sums those
// rows with the same row_sum, so they get the full relight's bits.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

#include "csr_zstd/csr_zstd.h"
#include "prtlab/base/error.h"

namespace prt::csr_zstd {
namespace {

typedef float Float4 __attribute__((vector_size(16)));

template <typename Column>
Rgb row_sum(const FrameView& v, const Column* columns, const Float4* light, float scale,
            std::size_t row) {
  const std::uint8_t* counts = v.counts;
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
  return Rgb(sum[0], sum[1], sum[2]);
}

// out[row] for the rows [begin, end) of frame v.
void product_rows(const FrameView& v, const Float4* light, float scale, std::size_t begin,
                  std::size_t end, Rgb* out) {
  for (std::size_t row = begin; row < end; ++row)
    out[row] = v.columns16 != nullptr ? row_sum(v, v.columns16, light, scale, row)
                                      : row_sum(v, v.columns32, light, scale, row);
}

std::vector<Float4> light4(const LightCoeffs& light) {
  std::vector<Float4> l4(light.values.size());
  for (std::size_t k = 0; k < l4.size(); ++k)
    l4[k] = Float4{light.values[k].x, light.values[k].y, light.values[k].z, 0.f};
  return l4;
}

}  // namespace

std::vector<FrameTask> frame_tasks(const FramedCsr& csr, std::span<const std::uint32_t> vertices) {
  std::vector<FrameTask> tasks;
  const auto m = static_cast<std::size_t>(csr.local_count);
  const auto b = static_cast<std::size_t>(csr.block_rows);
  if (m == 0) return tasks;
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const std::size_t first = vertices[i] * m, last = first + m - 1;
    for (std::size_t f = first / b; f <= last / b; ++f) {
      if (!tasks.empty() && tasks.back().frame == f) {
        tasks.back().vertex_end = i + 1;
      } else {
        tasks.push_back({f, i, i + 1});
      }
    }
  }
  return tasks;
}

void CsrZstdTransfer::relight(const LightCoeffs& light, LocalRadiance& out) const {
  const FramedCsr& csr = *csr_;
  check_pixel_light(light, static_cast<std::size_t>(csr.pixel_count), kName);
  out.ensure_shape(RadianceBasis::kPixel, csr.local_count, csr.vertices);
  const std::vector<Float4> l4 = light4(light);
  const float scale = static_cast<float>(csr.scale());
  Rgb* result = out.values.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, csr.frame_count(), 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t f = r.begin(); f != r.end(); ++f) {
                        const FrameView v = decoder_->decode(csr, f);
                        product_rows(v, l4.data(), scale, v.row_begin, v.row_end, result);
                      }
                    });
}

void CsrZstdTransfer::relight_vertices(const LightCoeffs& light,
                                       std::span<const std::uint32_t> vertices,
                                       LocalRadiance& out) const {
  const FramedCsr& csr = *csr_;
  check_pixel_light(light, static_cast<std::size_t>(csr.pixel_count), kName);
  check_vertex_subset(vertices, csr.vertices, kName);
  out.ensure_shape(RadianceBasis::kPixel, csr.local_count, csr.vertices);
  const std::vector<FrameTask> tasks = frame_tasks(csr, vertices);
  const std::vector<Float4> l4 = light4(light);
  const float scale = static_cast<float>(csr.scale());
  const auto m = static_cast<std::size_t>(csr.local_count);
  Rgb* result = out.values.data();
  // Each task writes only rows inside its frame, so tasks never write the same row.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tasks.size(), 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t t = r.begin(); t != r.end(); ++t) {
                        const FrameTask& task = tasks[t];
                        const FrameView v = decoder_->decode(csr, task.frame);
                        for (std::size_t i = task.vertex_begin; i < task.vertex_end; ++i) {
                          const std::size_t first = vertices[i] * m;
                          product_rows(v, l4.data(), scale, std::max(first, v.row_begin),
                                       std::min(first + m, v.row_end), result);
                        }
                      }
                    });
}

}  // namespace prt::csr_zstd
