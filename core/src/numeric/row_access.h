#pragma once
// Typed access to the rows of a RowSet. The algorithms are templates over these accessors and
// are instantiated once per storage type through visit_rows, so that the inner loops see the
// concrete element types. Every accessor walks a row in increasing column order: a dense row
// then sums exactly the same products as the CSR row holding its non-zeros (adding +0.0 does
// not change a sum), which makes the dense and sparse paths agree bit for bit.
#include <cstddef>
#include <cstdint>
#include <span>
#include <type_traits>
#include <utility>
#include <variant>

#include "prtlab/numeric/row_set.h"

namespace prt::numeric_detail {

template <class T>
class DenseRowAccess {
 public:
  DenseRowAccess(const RowSet& set, const T* data, std::ptrdiff_t row_stride,
                 std::ptrdiff_t col_stride)
      : set_(set), data_(data), row_stride_(row_stride), col_stride_(col_stride) {}

  std::size_t rows() const { return set_.rows(); }
  std::size_t cols() const { return set_.cols(); }

  /// Calls f(column, value) for every stored entry of row i, columns increasing.
  template <class F>
  void for_each(std::size_t i, F&& f) const {
    const T* row = data_ + static_cast<std::ptrdiff_t>(set_.stored_row(i)) * row_stride_;
    const std::size_t n = set_.cols();
    for (std::size_t j = 0; j < n; ++j) {
      f(j, static_cast<double>(row[static_cast<std::ptrdiff_t>(j) * col_stride_]));
    }
  }

 private:
  const RowSet& set_;
  const T* data_;
  std::ptrdiff_t row_stride_;
  std::ptrdiff_t col_stride_;
};

template <class Col, class Val>
class CsrRowAccess {
 public:
  CsrRowAccess(const RowSet& set, std::span<const std::uint32_t> offsets,
               std::span<const Col> columns, std::span<const Val> values, double scale)
      : set_(set), offsets_(offsets), columns_(columns), values_(values), scale_(scale) {}

  std::size_t rows() const { return set_.rows(); }
  std::size_t cols() const { return set_.cols(); }

  template <class F>
  void for_each(std::size_t i, F&& f) const {
    const std::size_t r = set_.stored_row(i);
    const std::size_t end = offsets_[r + 1];
    for (std::size_t e = offsets_[r]; e < end; ++e) {
      f(static_cast<std::size_t>(columns_[e]), static_cast<double>(values_[e]) * scale_);
    }
  }

 private:
  const RowSet& set_;
  std::span<const std::uint32_t> offsets_;
  std::span<const Col> columns_;
  std::span<const Val> values_;
  double scale_;
};

/// x_i . v for a dense vector v of length cols().
template <class Access>
double dot(const Access& a, std::size_t i, const double* v) {
  double s = 0.0;
  a.for_each(i, [&](std::size_t j, double x) { s += x * v[j]; });
  return s;
}

template <class Access>
double squared_norm(const Access& a, std::size_t i) {
  double s = 0.0;
  a.for_each(i, [&](std::size_t, double x) { s += x * x; });
  return s;
}

/// out += alpha * x_i.
template <class Access>
void axpy(const Access& a, std::size_t i, double alpha, double* out) {
  a.for_each(i, [&](std::size_t j, double x) { out[j] += alpha * x; });
}

/// Calls f(accessor) with the accessor matching the set's storage.
template <class F>
decltype(auto) visit_rows(const RowSet& set, F&& f) {
  return std::visit(
      [&](const auto& storage) -> decltype(auto) {
        using S = std::decay_t<decltype(storage)>;
        if constexpr (std::is_same_v<S, RowSet::Dense>) {
          return std::visit(
              [&](auto* data) -> decltype(auto) {
                using T = std::remove_cv_t<std::remove_pointer_t<decltype(data)>>;
                return f(DenseRowAccess<T>(set, data, storage.row_stride, storage.col_stride));
              },
              storage.data);
        } else {
          return std::visit(
              [&](auto columns, auto values) -> decltype(auto) {
                using C = std::remove_cv_t<typename decltype(columns)::element_type>;
                using V = std::remove_cv_t<typename decltype(values)::element_type>;
                return f(
                    CsrRowAccess<C, V>(set, storage.offsets, columns, values, storage.value_scale));
              },
              storage.columns, storage.values);
        }
      },
      set.storage());
}

}  // namespace prt::numeric_detail
