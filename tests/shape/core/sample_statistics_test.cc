#include "shape/core/sample_statistics.h"

#include <gtest/gtest.h>

#include <vector>

namespace pectus {
namespace {

// Quantiles by linear interpolation between order statistics, whatever the order of the sample: for
// 1..5 the median is 3, the 95th percentile 4.8 (position 3.8 of 0..4), the quartiles 2 and 4 (numpy's
// default gives the same).
TEST(SampleStatistics, QuantilesInterpolateBetweenOrderStatistics) {
  const std::vector<double> v = {5.0, 1.0, 4.0, 2.0, 3.0};
  EXPECT_DOUBLE_EQ(Quantile(v, 0.5), 3.0);
  EXPECT_DOUBLE_EQ(Quantile(v, 0.95), 4.8);
  EXPECT_DOUBLE_EQ(Quantile(v, 0.25), 2.0);
  EXPECT_DOUBLE_EQ(Quantile(v, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(Quantile(v, 1.0), 5.0);
  EXPECT_DOUBLE_EQ(Quantile({2.0, 4.0}, 0.5), 3.0);
  EXPECT_DOUBLE_EQ(Quantile({7.0}, 0.95), 7.0);
}

TEST(SampleStatistics, MeanAndMaxAndTheEmptySample) {
  const std::vector<double> v = {-1.0, 2.5, 0.5};
  EXPECT_DOUBLE_EQ(Mean(v), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(Max(v), 2.5);
  EXPECT_EQ(Quantile({}, 0.5), 0.0);
  EXPECT_EQ(Mean({}), 0.0);
  EXPECT_EQ(Max({}), 0.0);
}

}  // namespace
}  // namespace pectus
