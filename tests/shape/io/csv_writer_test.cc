// CSV tables: the exact text for a small table, with and without row names, and size mismatches refused.
#include "shape/io/csv_writer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

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

// Every number as printf's "%.10g" writes it (the stream the writer once used wrote the same): numbers of
// every magnitude, both signs, and the special values.
TEST(CsvText, WritesWhatPrintfWrites) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> mantissa(-10.0, 10.0);
  std::uniform_int_distribution<int> exponent(-320, 308);
  Eigen::MatrixXd v(1, 2000);
  for (Eigen::Index c = 0; c < v.cols(); ++c) v(0, c) = mantissa(rng) * std::pow(10.0, exponent(rng));
  const double special[] = {0.0,
                            -0.0,
                            1.0,
                            -1.0,
                            0.1,
                            1e-5,
                            123456789012.0,
                            9999999999.5,
                            std::numeric_limits<double>::infinity(),
                            -std::numeric_limits<double>::infinity(),
                            std::numeric_limits<double>::quiet_NaN(),
                            std::numeric_limits<double>::denorm_min(),
                            std::numeric_limits<double>::max()};
  for (std::size_t k = 0; k < std::size(special); ++k) v(0, static_cast<Eigen::Index>(k)) = special[k];
  std::string expected;
  char text[64];
  for (Eigen::Index c = 0; c < v.cols(); ++c) {
    std::snprintf(text, sizeof text, "%.10g", v(0, c));
    expected += (c ? "," : "") + std::string(text);
  }
  const std::vector<std::string> header(static_cast<std::size_t>(v.cols()), "c");
  const std::string csv = CsvText(header, v);
  EXPECT_EQ(csv.substr(csv.find('\n') + 1), expected + "\n");
}

TEST(CsvText, RefusesHeaderOrNamesOfTheWrongSize) {
  const Eigen::MatrixXd v = Eigen::MatrixXd::Zero(2, 2);
  EXPECT_THROW(CsvText({"a"}, v), Error);
  EXPECT_THROW(CsvText({"name", "a", "b"}, v, {"only one"}), Error);
  EXPECT_THROW(CsvText({"a", "b"}, v, {"s1", "s2"}), Error);  // the names' column needs a header too
}

}  // namespace
}  // namespace pectus
