// CSV tables: the exact text for a small table, with and without row names, and size mismatches refused.
#include "shape/io/csv_writer.h"

#include <gtest/gtest.h>

#include "shape/core/error.h"

namespace pectus {
namespace {

// A column-major matrix written row by row: each line holds one row's values in order (the pipeline once
// wrote rows of a column-major matrix by pointer, mixing subjects).
TEST(CsvText, WritesRowsInOrderWithTheirNames) {
  Eigen::MatrixXd v(2, 3);
  v << 1.5, -2.0, 3.0, 4.0, 0.125, 1e-12;
  EXPECT_EQ(CsvText({"subject", "a", "b", "c"}, v, {"s1", "s2"}),
            "subject,a,b,c\ns1,1.5,-2,3\ns2,4,0.125,1e-12\n");
  EXPECT_EQ(CsvText({"a", "b", "c"}, v), "a,b,c\n1.5,-2,3\n4,0.125,1e-12\n");
}

TEST(CsvText, KeepsTenSignificantDigits) {
  Eigen::MatrixXd v(1, 1);
  v << 3.14159265358979;
  EXPECT_EQ(CsvText({"pi"}, v), "pi\n3.141592654\n");
}

TEST(CsvText, RefusesHeaderOrNamesOfTheWrongSize) {
  const Eigen::MatrixXd v = Eigen::MatrixXd::Zero(2, 2);
  EXPECT_THROW(CsvText({"a"}, v), Error);
  EXPECT_THROW(CsvText({"name", "a", "b"}, v, {"only one"}), Error);
  EXPECT_THROW(CsvText({"a", "b"}, v, {"s1", "s2"}), Error);  // the names' column needs a header too
}

}  // namespace
}  // namespace pectus
