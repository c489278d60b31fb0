#include "shape/core/sample_statistics.h"

#include <gtest/gtest.h>

#include <algorithm>
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

// Several quantiles at once (by selection) equal those read off the sorted sample, ties included.
TEST(SampleStatistics, QuantilesBySelectionEqualTheSortedSamples) {
  std::vector<double> v;
  for (int i = 0; i < 1001; ++i) v.push_back(static_cast<double>((i * 7919) % 257) / 8.0);  // many ties
  std::vector<double> sorted = v;
  std::sort(sorted.begin(), sorted.end());
  const std::vector<double> qs = {0.0, 0.1, 0.5, 0.5, 0.9, 0.95, 0.99, 0.9995, 1.0};
  const std::vector<double> got = Quantiles(v, qs);
  for (std::size_t i = 0; i < qs.size(); ++i) {
    const double at = qs[i] * 1000.0;
    const auto lo = static_cast<std::size_t>(at);
    const double want = sorted[lo] + (at - static_cast<double>(lo)) *
                                         (sorted[std::min<std::size_t>(lo + 1, 1000)] - sorted[lo]);
    EXPECT_DOUBLE_EQ(got[i], want) << "q = " << qs[i];
  }
  EXPECT_EQ(Quantiles({}, {0.5, 0.9}), std::vector<double>({0.0, 0.0}));
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
