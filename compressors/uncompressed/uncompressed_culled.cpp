#include "uncompressed/uncompressed_culled.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>

#include "prtlab/base/error.h"
#include "prtlab/sphere/lit_faces.h"

namespace prt::uncompressed {
namespace {

// RGB + pad, as relight_exact's accumulators (core/src/transfer/exact_relight.cpp).
typedef float Float4 __attribute__((vector_size(16)));

template <typename Col>
struct RowSum {
  const std::uint32_t* offsets;
  const Col* cols;
  const std::uint8_t* counts;
  const Float4* light;
  const std::uint16_t* starts;  // kFaceStarts per row, or null
  std::uint32_t lit;
  float scale;

  Float4 term(std::uint32_t i) const { return static_cast<float>(counts[i]) * light[cols[i]]; }

  Rgb operator()(std::size_t row) const {
    const std::uint32_t b = offsets[row], e = offsets[row + 1];
    // relight_exact puts entry i of the row's full chunks of four into accumulator (i - b) % 4
    // and the tail into accumulator 0; every range below keeps that assignment and order.
    const std::uint32_t full = b + ((e - b) & ~3u);
    Float4 a[4] = {};
    auto range = [&](std::uint32_t lo, std::uint32_t hi) {
      std::uint32_t i = lo;
      const std::uint32_t stop = std::min(hi, full);
      for (; i < stop && ((i - b) & 3u) != 0; ++i) a[(i - b) & 3u] += term(i);
      for (; i + 4 <= stop; i += 4) {
        a[0] += term(i + 0);
        a[1] += term(i + 1);
        a[2] += term(i + 2);
        a[3] += term(i + 3);
      }
      for (; i < stop; ++i) a[(i - b) & 3u] += term(i);
      for (i = std::max(lo, full); i < hi; ++i) a[0] += term(i);
    };
    if (lit == kAllFaces || starts == nullptr) {
      range(b, e);
    } else {
      const std::uint16_t* s = starts + row * kFaceStarts;
      auto face_begin = [&](int f) { return f == 0 ? b : b + s[f - 1]; };
      for (int f = 0; f < kCubeFaces;) {
        if ((lit >> f & 1u) == 0) {
          ++f;
          continue;
        }
        int g = f;
        while (g < kCubeFaces && (lit >> g & 1u) != 0) ++g;  // one range over adjacent lit faces
        range(face_begin(f), g == kCubeFaces ? e : face_begin(g));
        f = g;
      }
    }
    const Float4 sum = ((a[0] + a[1]) + (a[2] + a[3])) * scale;
    return Rgb(sum[0], sum[1], sum[2]);
  }
};

template <typename Col>
void run(const TransferMatrix& t, const Col* cols, const FaceTable& faces,
         const std::vector<Float4>& light, std::uint32_t lit, bool all_vertices,
         std::span<const std::uint32_t> vertices, std::span<Rgb> out) {
  const RowSum<Col> sum{t.row_offsets().data(),
                        cols,
                        t.counts().data(),
                        light.data(),
                        faces.empty() ? nullptr : faces.starts().data(),
                        lit,
                        static_cast<float>(t.scale())};
  const std::size_t m = static_cast<std::size_t>(t.local_count());
  const std::size_t n = all_vertices ? t.vertex_count() : vertices.size();
  // 16 vertices (about 50 k non-zeros at M = 64) per task, as relight_exact's 1024 rows.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 16), [&](const auto& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      const std::size_t v = all_vertices ? i : vertices[i];
      for (std::size_t j = 0; j < m; ++j) out[v * m + j] = sum(v * m + j);
    }
  });
}

}  // namespace

FaceTable::FaceTable(const TransferMatrix& t) {
  const std::size_t n = t.cols();
  if (n % kCubeFaces != 0) return;
  const std::size_t per_face = n / kCubeFaces;
  const auto offsets = t.row_offsets();
  for (std::size_t row = 0; row < t.rows(); ++row)
    if (offsets[row + 1] - offsets[row] > std::numeric_limits<std::uint16_t>::max()) return;
  starts_.resize(t.rows() * kFaceStarts);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, t.rows(), 4096), [&](const auto& r) {
    for (std::size_t row = r.begin(); row < r.end(); ++row) {
      std::uint32_t i = offsets[row];
      const std::uint32_t e = offsets[row + 1];
      for (int f = 1; f < kCubeFaces; ++f) {
        while (i < e && t.column(i) < f * per_face) ++i;
        starts_[row * kFaceStarts + f - 1] = static_cast<std::uint16_t>(i - offsets[row]);
      }
    }
  });
}

void relight_culled(const TransferMatrix& t, const FaceTable& faces, std::span<const Rgb> light,
                    std::uint32_t lit, bool all_vertices, std::span<const std::uint32_t> vertices,
                    std::span<Rgb> out) {
  PRT_CHECK(light.size() == t.cols() && out.size() == t.rows(), "light {} / out {} vs {} x {}",
            light.size(), out.size(), t.rows(), t.cols());
  std::vector<Float4> l4(light.size());
  for (std::size_t k = 0; k < light.size(); ++k)
    l4[k] = Float4{light[k].x, light[k].y, light[k].z, 0.f};
  if (t.narrow_columns()) {
    run(t, t.columns16().data(), faces, l4, lit, all_vertices, vertices, out);
  } else {
    run(t, t.columns32().data(), faces, l4, lit, all_vertices, vertices, out);
  }
}

}  // namespace prt::uncompressed
