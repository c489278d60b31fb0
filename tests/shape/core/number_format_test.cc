#include "shape/core/number_format.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace pectus {
namespace {

TEST(NumberFormat, ThreeSignificantDigitsAtEverySize) {
  EXPECT_EQ(FormatSignificant(2.39732), "2.40");  // the bunny's Carr maximum, as it was printed
  EXPECT_EQ(FormatSignificant(0.0122981), "0.0123");
  EXPECT_EQ(FormatSignificant(0.001), "0.00100");
  EXPECT_EQ(FormatSignificant(37.449), "37.4");
  EXPECT_EQ(FormatSignificant(-37.451), "-37.5");
  EXPECT_EQ(FormatSignificant(1234.6), "1235");  // the integer part is never cut
  EXPECT_EQ(FormatSignificant(250000.0), "250000");
}

TEST(NumberFormat, RoundingIntoTheNextPowerOfTenKeepsTheDigits) {
  EXPECT_EQ(FormatSignificant(9.996), "10.0");
  EXPECT_EQ(FormatSignificant(0.09996), "0.100");
  EXPECT_EQ(FormatSignificant(999.7), "1000");
}

TEST(NumberFormat, TinyValuesAreScientific) {
  EXPECT_EQ(FormatSignificant(4.2e-5), "4.20e-05");
  EXPECT_EQ(FormatSignificant(-1e-9), "-1.00e-09");
}

TEST(NumberFormat, OtherDigitCounts) {
  EXPECT_EQ(FormatSignificant(2.39732, 1), "2");
  EXPECT_EQ(FormatSignificant(2.39732, 5), "2.3973");
  EXPECT_EQ(FormatSignificant(2.39732, 0), "2");  // at least one digit
}

TEST(NumberFormat, ZeroAndNonFinite) {
  EXPECT_EQ(FormatSignificant(0.0), "0");
  EXPECT_EQ(FormatSignificant(std::numeric_limits<double>::quiet_NaN()), "nan");
  EXPECT_EQ(FormatSignificant(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(FormatSignificant(-std::numeric_limits<double>::infinity()), "-inf");
}

TEST(NumberFormat, MillimetresCarryTheirUnit) {
  EXPECT_EQ(FormatMm(0.0268), "0.0268 mm");
  EXPECT_EQ(FormatMm(150.0), "150 mm");
}

}  // namespace
}  // namespace pectus
