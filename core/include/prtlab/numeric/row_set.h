#pragma once
// A read-only view of m points in R^n, stored either densely or as CSR rows. The numeric
// algorithms (k-means, truncated PCA) take this one type so that a backend can hand them the
// transfer matrix's own arrays (u16 or u32 columns, u8 counts with a scale) or a dense Eigen
// matrix without converting or densifying. A RowSet never owns its data: the arrays it was made
// from must outlive it.
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <span>
#include <variant>

namespace prt {

using RowMajorMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Column indices of a CSR matrix: u16 when the column count allows it, else u32.
using CsrColumns = std::variant<std::span<const std::uint16_t>, std::span<const std::uint32_t>>;
/// Stored values of a CSR matrix; each is multiplied by the RowSet's value scale on read, which
/// lets u8 counts c stand for c / s^2 exactly as TransferMatrix stores them.
using CsrValues =
    std::variant<std::span<const std::uint8_t>, std::span<const float>, std::span<const double>>;

class RowSet {
 public:
  /// Dense storage: element (i, j) is data[i * row_stride + j * col_stride].
  struct Dense {
    std::variant<const double*, const float*> data;
    std::ptrdiff_t row_stride = 0;
    std::ptrdiff_t col_stride = 0;
  };
  struct Csr {
    std::span<const std::uint32_t> offsets;
    CsrColumns columns;
    CsrValues values;
    double value_scale = 1.0;
  };

  /// Rows of a column-major Eigen matrix (the natural layout of Eigen::MatrixXd).
  static RowSet dense(const Eigen::MatrixXd& points);
  static RowSet dense(const RowMajorMatrixXd& points);
  /// rows x cols values stored row after row.
  static RowSet dense(std::span<const double> values, std::size_t rows, std::size_t cols);
  static RowSet dense(std::span<const float> values, std::size_t rows, std::size_t cols);
  /// CSR rows: offsets has rows + 1 entries, starting at 0; columns increase strictly within a
  /// row and are < cols. Throws ParameterError when the arrays are inconsistent.
  static RowSet csr(std::size_t cols, std::span<const std::uint32_t> offsets, CsrColumns columns,
                    CsrValues values, double value_scale = 1.0);

  /// The rows listed in `rows` (indices into this set, repeats allowed), in that order. Lets a
  /// clustered backend run PCA on one cluster without copying its rows. The index array must
  /// outlive the result; a subset of a subset is refused.
  RowSet subset(std::span<const std::uint32_t> rows) const;

  std::size_t rows() const { return has_selection_ ? selection_.size() : rows_; }
  std::size_t cols() const { return cols_; }
  bool is_sparse() const { return std::holds_alternative<Csr>(storage_); }

  /// The rows as a dense matrix, for tests and small sets only.
  Eigen::MatrixXd to_dense() const;

  const std::variant<Dense, Csr>& storage() const { return storage_; }
  /// The stored row behind row i of this view.
  std::size_t stored_row(std::size_t i) const { return has_selection_ ? selection_[i] : i; }
  bool has_selection() const { return has_selection_; }

 private:
  RowSet(std::variant<Dense, Csr> storage, std::size_t rows, std::size_t cols)
      : storage_(storage), rows_(rows), cols_(cols) {}

  std::variant<Dense, Csr> storage_;
  std::size_t rows_ = 0;
  std::size_t cols_ = 0;
  std::span<const std::uint32_t> selection_;
  bool has_selection_ = false;
};

}  // namespace prt
