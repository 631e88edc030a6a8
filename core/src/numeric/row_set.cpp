#include "prtlab/numeric/row_set.h"

#include <fmt/format.h>

#include <cmath>

#include "numeric/row_access.h"
#include "prtlab/base/error.h"

namespace prt {

namespace {

template <class T>
RowSet::Dense row_major(const T* data, std::size_t cols) {
  return RowSet::Dense{data, static_cast<std::ptrdiff_t>(cols), 1};
}

template <class T>
void check_row_major(std::span<const T> values, std::size_t rows, std::size_t cols) {
  if (values.size() != rows * cols) {
    throw ParameterError(
        fmt::format("RowSet::dense: {} values given for {} rows of {} columns (expected {})",
                    values.size(), rows, cols, rows * cols));
  }
}

}  // namespace

RowSet RowSet::dense(const Eigen::MatrixXd& points) {
  return RowSet(Dense{points.data(), 1, static_cast<std::ptrdiff_t>(points.rows())},
                static_cast<std::size_t>(points.rows()), static_cast<std::size_t>(points.cols()));
}

RowSet RowSet::dense(const RowMajorMatrixXd& points) {
  return RowSet(row_major(points.data(), static_cast<std::size_t>(points.cols())),
                static_cast<std::size_t>(points.rows()), static_cast<std::size_t>(points.cols()));
}

RowSet RowSet::dense(std::span<const double> values, std::size_t rows, std::size_t cols) {
  check_row_major(values, rows, cols);
  return RowSet(row_major(values.data(), cols), rows, cols);
}

RowSet RowSet::dense(std::span<const float> values, std::size_t rows, std::size_t cols) {
  check_row_major(values, rows, cols);
  return RowSet(row_major(values.data(), cols), rows, cols);
}

RowSet RowSet::csr(std::size_t cols, std::span<const std::uint32_t> offsets, CsrColumns columns,
                   CsrValues values, double value_scale) {
  if (offsets.empty() || offsets.front() != 0) {
    throw ParameterError("RowSet::csr: the row offsets must have rows + 1 entries, starting at 0");
  }
  const std::size_t nnz = offsets.back();
  const std::size_t column_count = std::visit([](auto c) { return c.size(); }, columns);
  const std::size_t value_count = std::visit([](auto v) { return v.size(); }, values);
  if (column_count != nnz || value_count != nnz) {
    throw ParameterError(fmt::format(
        "RowSet::csr: the offsets end at {} entries but {} column indices and {} values are given",
        nnz, column_count, value_count));
  }
  if (!std::isfinite(value_scale)) {
    throw ParameterError("RowSet::csr: the value scale must be finite");
  }
  const std::size_t rows = offsets.size() - 1;
  std::visit(
      [&](auto c) {
        for (std::size_t r = 0; r < rows; ++r) {
          if (offsets[r + 1] < offsets[r]) {
            throw ParameterError(fmt::format("RowSet::csr: row offsets decrease at row {}", r));
          }
          for (std::size_t e = offsets[r]; e < offsets[r + 1]; ++e) {
            if (c[e] >= cols || (e > offsets[r] && c[e] <= c[e - 1])) {
              throw ParameterError(
                  fmt::format("RowSet::csr: row {} has column {} out of order or not below {}", r,
                              static_cast<std::size_t>(c[e]), cols));
            }
          }
        }
      },
      columns);
  return RowSet(Csr{offsets, columns, values, value_scale}, rows, cols);
}

RowSet RowSet::subset(std::span<const std::uint32_t> rows) const {
  if (has_selection_) {
    throw ParameterError("RowSet::subset: the set is already a subset; index the stored rows");
  }
  for (const std::uint32_t r : rows) {
    if (r >= rows_) {
      throw ParameterError(
          fmt::format("RowSet::subset: row {} is out of range (the set has {} rows)", r, rows_));
    }
  }
  RowSet s = *this;
  s.selection_ = rows;
  s.has_selection_ = true;
  return s;
}

Eigen::MatrixXd RowSet::to_dense() const {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(this->rows()),
                                              static_cast<Eigen::Index>(cols_));
  numeric_detail::visit_rows(*this, [&](const auto& a) {
    for (std::size_t i = 0; i < a.rows(); ++i) {
      a.for_each(i, [&](std::size_t j, double x) {
        out(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = x;
      });
    }
  });
  return out;
}

}  // namespace prt
