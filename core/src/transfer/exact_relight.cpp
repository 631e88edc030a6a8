#include "prtlab/transfer/exact_relight.h"

#include <tbb/parallel_for.h>

#include "prtlab/base/error.h"

namespace prt {

namespace {

// RGB + pad in one 16-byte lane: one aligned load per gathered light value, and the compiler
// keeps the accumulators in SSE registers without relying on auto-vectorisation.
typedef float Float4 __attribute__((vector_size(16)));

std::vector<Float4> padded_light(std::span<const Rgb> light) {
  std::vector<Float4> out(light.size());
  for (std::size_t k = 0; k < light.size(); ++k)
    out[k] = Float4{light[k].x, light[k].y, light[k].z, 0.f};
  return out;
}

template <typename Col>
void product_rows(std::size_t begin, std::size_t end, const std::uint32_t* offsets, const Col* cols,
                  const std::uint8_t* counts, const Float4* light, float scale, Rgb* out) {
  for (std::size_t row = begin; row < end; ++row) {
    // Four independent accumulators hide the add latency of one dependent chain.
    Float4 a0{}, a1{}, a2{}, a3{};
    std::uint32_t i = offsets[row];
    const std::uint32_t e = offsets[row + 1];
    for (; i + 4 <= e; i += 4) {
      a0 += static_cast<float>(counts[i + 0]) * light[cols[i + 0]];
      a1 += static_cast<float>(counts[i + 1]) * light[cols[i + 1]];
      a2 += static_cast<float>(counts[i + 2]) * light[cols[i + 2]];
      a3 += static_cast<float>(counts[i + 3]) * light[cols[i + 3]];
    }
    for (; i < e; ++i) a0 += static_cast<float>(counts[i]) * light[cols[i]];
    const Float4 sum = ((a0 + a1) + (a2 + a3)) * scale;
    out[row] = Rgb(sum[0], sum[1], sum[2]);
  }
}

void check_shapes(const TransferMatrix& t, std::size_t light, std::size_t out) {
  if (light != t.cols()) {
    throw ParameterError(fmt::format(
        "relight: the light has {} values, the transfer has N = {} columns", light, t.cols()));
  }
  if (out != t.rows()) {
    throw ParameterError(
        fmt::format("relight: the output has {} values, the transfer has {} rows", out, t.rows()));
  }
}

}  // namespace

void relight_exact(const TransferMatrix& t, std::span<const Rgb> light, std::span<Rgb> out,
                   RelightThreads threads) {
  check_shapes(t, light.size(), out.size());
  const std::vector<Float4> l4 = padded_light(light);
  const float scale = static_cast<float>(t.scale());
  auto run = [&](std::size_t b, std::size_t e) {
    if (t.narrow_columns()) {
      product_rows(b, e, t.row_offsets().data(), t.columns16().data(), t.counts().data(), l4.data(),
                   scale, out.data());
    } else {
      product_rows(b, e, t.row_offsets().data(), t.columns32().data(), t.counts().data(), l4.data(),
                   scale, out.data());
    }
  };
  if (threads == RelightThreads::kOne) {
    run(0, t.rows());
    return;
  }
  // 1024 rows (16 vertices at M = 64, about 50 k non-zeros) per task: enough work to amortise
  // the scheduling, fine enough to balance unequal occlusion across vertices.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, t.rows(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) { run(r.begin(), r.end()); });
}

LocalRadiance relight_exact(const TransferMatrix& t, std::span<const Rgb> light) {
  LocalRadiance out(RadianceBasis::kPixel, t.local_count(), t.vertex_count());
  relight_exact(t, light, out.values);
  return out;
}

std::vector<Vec3d> relight_exact_double(const TransferMatrix& t, std::span<const Rgb> light) {
  std::vector<Vec3d> out(t.rows());
  check_shapes(t, light.size(), out.size());
  const auto offsets = t.row_offsets();
  const auto counts = t.counts();
  const double scale = t.scale();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, t.rows(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t row = r.begin(); row != r.end(); ++row) {
                        Vec3d acc{0.0};
                        for (std::uint32_t i = offsets[row]; i < offsets[row + 1]; ++i)
                          acc += static_cast<double>(counts[i]) * Vec3d(light[t.column(i)]);
                        out[row] = acc * scale;
                      }
                    });
  return out;
}

EigenSparseTransfer::EigenSparseTransfer(const TransferMatrix& t)
    : matrix_(static_cast<Eigen::Index>(t.rows()), static_cast<Eigen::Index>(t.cols())) {
  PRT_CHECK(t.nnz() <= static_cast<std::size_t>(std::numeric_limits<int>::max()),
            "Eigen baseline: {} non-zeros exceed its int indices", t.nnz());
  // Fill the compressed arrays directly: rows are already sorted, so no triplet sort.
  matrix_.resizeNonZeros(static_cast<Eigen::Index>(t.nnz()));
  const auto offsets = t.row_offsets();
  for (std::size_t r = 0; r <= t.rows(); ++r)
    matrix_.outerIndexPtr()[r] = static_cast<int>(offsets[r]);
  const float scale = static_cast<float>(t.scale());
  for (std::size_t i = 0; i < t.nnz(); ++i) {
    matrix_.innerIndexPtr()[i] = static_cast<int>(t.column(i));
    matrix_.valuePtr()[i] = t.counts()[i] * scale;
  }
}

EigenSparseTransfer::Dense EigenSparseTransfer::to_dense(std::span<const Rgb> light) {
  Dense d(static_cast<Eigen::Index>(light.size()), 3);
  for (std::size_t k = 0; k < light.size(); ++k) {
    d(static_cast<Eigen::Index>(k), 0) = light[k].x;
    d(static_cast<Eigen::Index>(k), 1) = light[k].y;
    d(static_cast<Eigen::Index>(k), 2) = light[k].z;
  }
  return d;
}

void EigenSparseTransfer::relight(std::span<const Rgb> light, std::span<Rgb> out) const {
  if (light.size() != static_cast<std::size_t>(matrix_.cols()) ||
      out.size() != static_cast<std::size_t>(matrix_.rows())) {
    throw ParameterError(
        fmt::format("Eigen relight: light {} / output {} values for a {} x {} transfer",
                    light.size(), out.size(), matrix_.rows(), matrix_.cols()));
  }
  Dense result;
  multiply(to_dense(light), result);
  for (std::size_t r = 0; r < out.size(); ++r) {
    const auto i = static_cast<Eigen::Index>(r);
    out[r] = Rgb(result(i, 0), result(i, 1), result(i, 2));
  }
}

}  // namespace prt
