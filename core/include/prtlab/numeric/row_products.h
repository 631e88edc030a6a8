#pragma once
// Products of the rows of a RowSet with dense matrices: the one sparse x dense product per pass
// that CPCA's classification and its weight computation reduce to. A CSR row costs its
// non-zeros times the width of the dense matrix; each non-zero adds a scaled contiguous row of
// the (row-major) dense matrix, so the inner loop is a unit-stride axpy that the compiler
// vectorises (an AVX2+FMA clone is chosen at run time where the CPU has it).
#include <Eigen/Core>
#include <cstdint>
#include <span>

#include "prtlab/numeric/row_set.h"

namespace prt {

using RowMajorMatrixXf = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// y = x_i B for one row i of `rows` and a dense cols x K row-major B; `y` has K entries and is
/// overwritten. The products are summed in stored-entry order, so the result of a row does not
/// depend on how rows are shared between threads.
void multiply_row(const RowSet& rows, std::size_t i, const RowMajorMatrixXf& b, std::span<float> y);
void multiply_row(const RowSet& rows, std::size_t i, const RowMajorMatrixXd& b,
                  std::span<double> y);

/// Y = X B for all rows (m x K row-major), in parallel over rows, each row as multiply_row.
RowMajorMatrixXf multiply_rows(const RowSet& rows, const RowMajorMatrixXf& b);
RowMajorMatrixXd multiply_rows(const RowSet& rows, const RowMajorMatrixXd& b);

/// ||x_i||^2 of every row, in double.
Eigen::VectorXd row_squared_norms(const RowSet& rows);

/// out[0..n) += a * x[0..n): the kernel of the products above (exposed for the benchmark that
/// compares it with the machine's peak).
void axpy_f32(float a, const float* x, float* out, std::size_t n);
void axpy_f64(double a, const double* x, double* out, std::size_t n);

/// GFLOP/s of a register-resident stream of independent float multiply-adds on one thread (a
/// peak to compare the products with), measured for about `seconds`.
double measured_fma_gflops_per_thread(double seconds = 0.2);

}  // namespace prt
