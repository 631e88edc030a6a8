// RowSet: every storage reads back the same rows, subsets select and reorder, and inconsistent
// CSR arrays are refused.
#include <gtest/gtest.h>

#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/numeric/row_set.h"

namespace prt {
namespace {

TEST(RowSet, EveryStorageReadsTheSameRows) {
  Eigen::MatrixXd expected(3, 4);
  expected << 0, 0.5, 0, 1.5,  //
      0, 0, 0, 0,              //
      2.0, 0, 0.25, 0;
  const RowMajorMatrixXd row_major = expected;
  std::vector<double> flat(row_major.data(), row_major.data() + 12);
  std::vector<float> flat_f(flat.begin(), flat.end());
  const std::vector<std::uint32_t> offsets{0, 2, 2, 4};
  const std::vector<std::uint16_t> cols16{1, 3, 0, 2};
  const std::vector<std::uint32_t> cols32{1, 3, 0, 2};
  const std::vector<std::uint8_t> counts{2, 6, 8, 1};  // times 1/4
  const std::vector<double> values{0.5, 1.5, 2.0, 0.25};

  const RowSet sets[] = {
      RowSet::dense(expected),
      RowSet::dense(row_major),
      RowSet::dense(std::span<const double>(flat), 3, 4),
      RowSet::dense(std::span<const float>(flat_f), 3, 4),
      RowSet::csr(4, offsets, std::span<const std::uint16_t>(cols16),
                  std::span<const std::uint8_t>(counts), 0.25),
      RowSet::csr(4, offsets, std::span<const std::uint32_t>(cols32),
                  std::span<const double>(values)),
  };
  for (const RowSet& s : sets) {
    EXPECT_EQ(s.rows(), 3u);
    EXPECT_EQ(s.cols(), 4u);
    EXPECT_EQ(s.to_dense(), expected);
  }
  EXPECT_TRUE(sets[4].is_sparse());
  EXPECT_FALSE(sets[0].is_sparse());
}

TEST(RowSet, SubsetSelectsAndReorders) {
  Eigen::MatrixXd x(4, 2);
  x << 1, 2, 3, 4, 5, 6, 7, 8;
  const std::vector<std::uint32_t> pick{3, 0, 3};
  const RowSet s = RowSet::dense(x).subset(pick);
  EXPECT_EQ(s.rows(), 3u);
  Eigen::MatrixXd expected(3, 2);
  expected << 7, 8, 1, 2, 7, 8;
  EXPECT_EQ(s.to_dense(), expected);
  EXPECT_THROW(s.subset(pick), ParameterError);
  const std::vector<std::uint32_t> bad{4};
  EXPECT_THROW(RowSet::dense(x).subset(bad), ParameterError);
  const std::vector<std::uint32_t> none;
  EXPECT_EQ(RowSet::dense(x).subset(none).rows(), 0u);
}

TEST(RowSet, RefusesInconsistentCsr) {
  const std::vector<std::uint16_t> cols{0, 2, 1};
  const std::vector<double> vals{1, 2, 3};
  auto make = [&](std::vector<std::uint32_t> offsets, std::size_t ncols,
                  std::vector<std::uint16_t> c) {
    static std::vector<std::uint32_t> keep_offsets;
    static std::vector<std::uint16_t> keep_cols;
    keep_offsets = std::move(offsets);
    keep_cols = std::move(c);
    return RowSet::csr(ncols, keep_offsets, std::span<const std::uint16_t>(keep_cols),
                       std::span<const double>(vals));
  };
  EXPECT_NO_THROW(make({0, 2, 3}, 3, cols));
  EXPECT_THROW(make({}, 3, cols), ParameterError);
  EXPECT_THROW(make({1, 2, 3}, 3, cols), ParameterError);       // does not start at 0
  EXPECT_THROW(make({0, 2, 4}, 3, cols), ParameterError);       // more entries than given
  EXPECT_THROW(make({0, 2, 1, 3}, 3, cols), ParameterError);    // decreasing
  EXPECT_THROW(make({0, 2, 3}, 2, cols), ParameterError);       // column 2 of 2
  EXPECT_THROW(make({0, 2, 3}, 3, {2, 0, 1}), ParameterError);  // unsorted row
  EXPECT_THROW(make({0, 2, 3}, 3, {1, 1, 1}), ParameterError);  // repeated column
  EXPECT_THROW(RowSet::dense(std::span<const double>(vals), 2, 2), ParameterError);
}

}  // namespace
}  // namespace prt
