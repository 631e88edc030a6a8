// The C++ relight of backend `haar`: the reference of haar.cl. The light's transform is computed
// in double and rounded to float (the kernel sums each coefficient's support in float, so the two
// agree to float rounding); every row then sums its terms with four accumulators combined as
// (a0 + a1) + (a2 + a3), the kernel's order. The full and the vertex-subset relight share RowSum,
// so a subset row has the full relight's bits.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <bit>

#include "haar/haar.h"
#include "haar/haar_wavelet.h"
#include "prtlab/base/error.h"

namespace prt::haar {
namespace {

typedef float Float4 __attribute__((vector_size(16)));

inline float half_bits_to_float(std::uint16_t half) {
  // Finite halves only (load() refuses the others): the 15 magnitude bits moved into float
  // position give 2^-112 times the value, for normal and subnormal halves alike.
  const std::uint32_t magnitude = static_cast<std::uint32_t>(half & 0x7fffu) << 13;
  const float value = std::bit_cast<float>(magnitude) * 0x1p112f;
  const std::uint32_t sign = static_cast<std::uint32_t>(half & 0x8000u) << 16;
  return std::bit_cast<float>(std::bit_cast<std::uint32_t>(value) | sign);
}

template <typename Index, typename Value>
struct RowSum {
  const std::uint32_t* offsets;
  const Index* indices;
  Value value;
  const float* row_scales;  // s8 only, else null
  const Float4* light;      // W L

  Rgb operator()(std::size_t row) const {
    Float4 a0{}, a1{}, a2{}, a3{};
    std::uint32_t i = offsets[row];
    const std::uint32_t e = offsets[row + 1];
    for (; i + 4 <= e; i += 4) {
      a0 += value(i + 0) * light[indices[i + 0]];
      a1 += value(i + 1) * light[indices[i + 1]];
      a2 += value(i + 2) * light[indices[i + 2]];
      a3 += value(i + 3) * light[indices[i + 3]];
    }
    for (; i < e; ++i) a0 += value(i) * light[indices[i]];
    Float4 sum = (a0 + a1) + (a2 + a3);
    if (row_scales != nullptr) sum *= row_scales[row];
    return Rgb(sum[0], sum[1], sum[2]);
  }
};

template <typename Fn>
void with_row_sum(const HaarArrays& a, const Float4* light, const Fn& fn) {
  const auto by_index = [&](const auto* indices) {
    using Index = std::remove_cvref_t<decltype(*indices)>;
    switch (a.format) {
      case ValueFormat::kFloat32: {
        const float* v = a.values32.data();
        const auto value = [v](std::uint32_t i) { return v[i]; };
        fn(RowSum<Index, decltype(value)>{a.offsets.data(), indices, value, nullptr, light});
        break;
      }
      case ValueFormat::kFloat16: {
        const std::uint16_t* v = a.values16.data();
        const auto value = [v](std::uint32_t i) { return half_bits_to_float(v[i]); };
        fn(RowSum<Index, decltype(value)>{a.offsets.data(), indices, value, nullptr, light});
        break;
      }
      case ValueFormat::kS8: {
        const std::int8_t* c = a.codes.data();
        const auto value = [c](std::uint32_t i) { return static_cast<float>(c[i]); };
        fn(RowSum<Index, decltype(value)>{a.offsets.data(), indices, value, a.row_scales.data(),
                                          light});
        break;
      }
    }
  };
  if (a.wide) {
    by_index(a.indices32.data());
  } else {
    by_index(a.indices16.data());
  }
}

std::vector<Float4> light4(const HaarArrays& a, std::span<const Rgb> coefficients,
                           std::size_t out) {
  PRT_CHECK(coefficients.size() == static_cast<std::size_t>(a.pixel_count) && out == a.rows(),
            "haar relight: light {} / output {} values for {} rows x {} columns",
            coefficients.size(), out, a.rows(), a.pixel_count);
  std::vector<Float4> l4(coefficients.size());
  for (std::size_t k = 0; k < coefficients.size(); ++k)
    l4[k] = Float4{coefficients[k].x, coefficients[k].y, coefficients[k].z, 0.f};
  return l4;
}

void relight_rows(const HaarArrays& a, const std::vector<Float4>& l4, std::span<Rgb> out) {
  with_row_sum(a, l4.data(), [&](const auto& sum) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, a.rows(), 1024), [&](const auto& r) {
      for (std::size_t row = r.begin(); row < r.end(); ++row) out[row] = sum(row);
    });
  });
}

void relight_rows_of(const HaarArrays& a, const std::vector<Float4>& l4,
                     std::span<const std::uint32_t> vertices, std::span<Rgb> out) {
  const auto m = static_cast<std::size_t>(a.local_count);
  with_row_sum(a, l4.data(), [&](const auto& sum) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertices.size(), 16), [&](const auto& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i) {
        const std::size_t v = vertices[i];
        for (std::size_t j = 0; j < m; ++j) out[v * m + j] = sum(v * m + j);
      }
    });
  });
}

}  // namespace

std::vector<Rgb> transform_light(std::span<const Rgb> light, int resolution) {
  std::vector<double> channel(light.size());
  std::vector<Rgb> out(light.size());
  for (int c = 0; c < 3; ++c) {
    for (std::size_t k = 0; k < light.size(); ++k) channel[k] = light[k][c];
    forward_cubemap(channel, resolution);
    for (std::size_t k = 0; k < light.size(); ++k) out[k][c] = static_cast<float>(channel[k]);
  }
  return out;
}

void relight_haar(const HaarArrays& a, std::span<const Rgb> light, std::span<Rgb> out) {
  PRT_CHECK(light.size() == static_cast<std::size_t>(a.pixel_count),
            "haar relight: light {} values for {} columns", light.size(), a.pixel_count);
  relight_rows(a, light4(a, transform_light(light, a.resolution), out.size()), out);
}

void relight_haar_vertices(const HaarArrays& a, std::span<const Rgb> light,
                           std::span<const std::uint32_t> vertices, std::span<Rgb> out) {
  PRT_CHECK(light.size() == static_cast<std::size_t>(a.pixel_count),
            "haar relight: light {} values for {} columns", light.size(), a.pixel_count);
  relight_rows_of(a, light4(a, transform_light(light, a.resolution), out.size()), vertices, out);
}

void relight_haar_wavelet(const HaarArrays& a, std::span<const Rgb> coefficients,
                          std::span<Rgb> out) {
  relight_rows(a, light4(a, coefficients, out.size()), out);
}

void relight_haar_wavelet_vertices(const HaarArrays& a, std::span<const Rgb> coefficients,
                                   std::span<const std::uint32_t> vertices, std::span<Rgb> out) {
  relight_rows_of(a, light4(a, coefficients, out.size()), vertices, out);
}

}  // namespace prt::haar
