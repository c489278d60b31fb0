#include "registration/robust_loss.h"

#include <gtest/gtest.h>

#include <vector>

#include "shape/core/error.h"

namespace pectus {
namespace {

TEST(RobustLoss, WeightsAtKnownResiduals) {
  EXPECT_DOUBLE_EQ(RobustWeight(RobustLoss::kNone, 7.0, 1.0), 1.0);
  EXPECT_DOUBLE_EQ(RobustWeight(RobustLoss::kHuber, 0.5, 1.0), 1.0);
  EXPECT_DOUBLE_EQ(RobustWeight(RobustLoss::kHuber, -2.0, 1.0), 0.5);
  EXPECT_DOUBLE_EQ(RobustWeight(RobustLoss::kCauchy, 1.0, 1.0), 0.5);
  EXPECT_DOUBLE_EQ(RobustWeight(RobustLoss::kTukey, 0.5, 1.0), 0.5625);
  EXPECT_DOUBLE_EQ(RobustWeight(RobustLoss::kTukey, 1.5, 1.0), 0.0);
  EXPECT_EQ(ParseRobustLoss("tukey"), RobustLoss::kTukey);
  EXPECT_THROW(ParseRobustLoss("l1"), Error);
}

TEST(RobustLoss, MadScaleOfKnownSample) {
  std::vector<double> r = {0.1, 0.2, 0.3, 0.4, 100.0};
  EXPECT_NEAR(MadScale(&r), 1.4826 * 0.3, 1e-12);
  std::vector<double> empty;
  EXPECT_EQ(MadScale(&empty), 0.0);
}

}  // namespace
}  // namespace pectus
