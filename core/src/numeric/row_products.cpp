#include "prtlab/numeric/row_products.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>

#include "numeric/row_access.h"
#include "prtlab/base/error.h"

// The build is portable (no -march): the hot loops get an AVX2+FMA clone picked at load time.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && \
    !defined(__SANITIZE_ADDRESS__)
#define PRT_VECTOR_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define PRT_VECTOR_CLONES
#endif

namespace prt {

PRT_VECTOR_CLONES void axpy_f32(float a, const float* x, float* out, std::size_t n) {
  for (std::size_t k = 0; k < n; ++k) out[k] += a * x[k];
}

PRT_VECTOR_CLONES void axpy_f64(double a, const double* x, double* out, std::size_t n) {
  for (std::size_t k = 0; k < n; ++k) out[k] += a * x[k];
}

namespace {

void axpy(float a, const float* x, float* out, std::size_t n) {
  axpy_f32(a, x, out, n);
}
void axpy(double a, const double* x, double* out, std::size_t n) {
  axpy_f64(a, x, out, n);
}

template <class Scalar>
using RowMajor = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

template <class Scalar>
void check_product(const RowSet& rows, const RowMajor<Scalar>& b, std::size_t y_size) {
  if (static_cast<std::size_t>(b.rows()) != rows.cols()) {
    throw ParameterError(fmt::format("multiply_rows: the rows have {} columns, the matrix {} rows",
                                     rows.cols(), b.rows()));
  }
  if (y_size != static_cast<std::size_t>(b.cols())) {
    throw ParameterError(
        fmt::format("multiply_rows: the output has {} entries, the product {}", y_size, b.cols()));
  }
}

template <class Access, class Scalar>
void row_times(const Access& a, std::size_t i, const RowMajor<Scalar>& b, Scalar* y) {
  const auto k = static_cast<std::size_t>(b.cols());
  std::fill(y, y + k, Scalar(0));
  a.for_each(
      i, [&](std::size_t j, double v) { axpy(static_cast<Scalar>(v), b.data() + j * k, y, k); });
}

template <class Scalar>
RowMajor<Scalar> all_rows_times(const RowSet& rows, const RowMajor<Scalar>& b) {
  check_product<Scalar>(rows, b, static_cast<std::size_t>(b.cols()));
  RowMajor<Scalar> y(static_cast<Eigen::Index>(rows.rows()), b.cols());
  numeric_detail::visit_rows(rows, [&](const auto& a) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, a.rows(), 256), [&](const auto& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        row_times(a, i, b, y.data() + i * static_cast<std::size_t>(b.cols()));
      }
    });
  });
  return y;
}

// 64 independent accumulators: enough multiply-adds in flight to cover the FMA latency on every
// current x86 core, and they stay in registers.
PRT_VECTOR_CLONES float fma_stream(std::int64_t iterations, float a, float b) {
  float acc[64];
  for (int j = 0; j < 64; ++j) acc[j] = static_cast<float>(j) * 1e-3f;
  for (std::int64_t it = 0; it < iterations; ++it) {
    for (int j = 0; j < 64; ++j) acc[j] = acc[j] * a + b;
  }
  float s = 0.f;
  for (int j = 0; j < 64; ++j) s += acc[j];
  return s;
}

}  // namespace

void multiply_row(const RowSet& rows, std::size_t i, const RowMajorMatrixXf& b,
                  std::span<float> y) {
  check_product<float>(rows, b, y.size());
  numeric_detail::visit_rows(rows, [&](const auto& a) { row_times(a, i, b, y.data()); });
}

void multiply_row(const RowSet& rows, std::size_t i, const RowMajorMatrixXd& b,
                  std::span<double> y) {
  check_product<double>(rows, b, y.size());
  numeric_detail::visit_rows(rows, [&](const auto& a) { row_times(a, i, b, y.data()); });
}

RowMajorMatrixXf multiply_rows(const RowSet& rows, const RowMajorMatrixXf& b) {
  return all_rows_times<float>(rows, b);
}

RowMajorMatrixXd multiply_rows(const RowSet& rows, const RowMajorMatrixXd& b) {
  return all_rows_times<double>(rows, b);
}

Eigen::VectorXd row_squared_norms(const RowSet& rows) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(rows.rows()));
  numeric_detail::visit_rows(rows, [&](const auto& a) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, a.rows(), 1024), [&](const auto& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        out[static_cast<Eigen::Index>(i)] = numeric_detail::squared_norm(a, i);
      }
    });
  });
  return out;
}

double measured_fma_gflops_per_thread(double seconds) {
  using Clock = std::chrono::steady_clock;
  std::int64_t iterations = 1 << 16;
  volatile float sink = 0.f;
  for (;;) {
    const auto t0 = Clock::now();
    sink = sink + fma_stream(iterations, 0.999999f, 1e-7f);
    const double dt = std::chrono::duration<double>(Clock::now() - t0).count();
    if (dt >= seconds || iterations > (std::int64_t{1} << 40)) {
      return 2.0 * 64.0 * static_cast<double>(iterations) / dt * 1e-9;
    }
    iterations *= 2;
  }
}

}  // namespace prt
