// Growth compensation recovers a known growth scale and pose from landmarks, and keeps a given scale.
#include "shape/model/growth_compensation.h"

#include <gtest/gtest.h>

#include "shape/core/error.h"

namespace pectus {
namespace {

LandmarkSet Pre() {
  LandmarkSet s;
  s.items.push_back({"sternal_notch", {0, 0, 0}, ""});
  s.items.push_back({"xiphoid", {0, 160, 10}, ""});
  s.items.push_back({"costal_cartilage_1_left", {40, 15, -5}, ""});
  s.items.push_back({"manubrium", {0, 30, 3}, ""});
  return s;
}

Similarity3 Growth() {
  Similarity3 T;
  T.scale = 1.08;
  T.rotation = Eigen::AngleAxisd(0.2, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  T.translation = Eigen::Vector3d(5, -20, 12);
  return T;
}

TEST(GrowthCompensation, EstimatesAKnownScaleFromLandmarks) {
  const GrowthCompensationResult r = CompensateGrowth(Pre(), Pre().Transformed(Growth()));
  EXPECT_TRUE(r.estimated);
  EXPECT_NEAR(r.scale, 1.08, 1e-10);
  EXPECT_TRUE(r.T_post_pre.rotation.isApprox(Growth().rotation, 1e-10));
  EXPECT_TRUE(r.T_post_pre.translation.isApprox(Growth().translation, 1e-8));
  EXPECT_LT(r.rms_mm, 1e-9);
  EXPECT_EQ(r.labels.size(), 4u);
}

TEST(GrowthCompensation, KeepsAGivenScaleAndFitsThePose) {
  GrowthCompensationOptions o;
  o.scale = 1.08;
  const GrowthCompensationResult r = CompensateGrowth(Pre(), Pre().Transformed(Growth()), o);
  EXPECT_FALSE(r.estimated);
  EXPECT_DOUBLE_EQ(r.scale, 1.08);
  const Eigen::Vector3d x(10, 50, 2);
  EXPECT_TRUE((r.T_post_pre * x).isApprox(Growth() * x, 1e-9));
  o.scale = -1.0;
  EXPECT_THROW(CompensateGrowth(Pre(), Pre(), o), Error);
}

TEST(GrowthCompensation, ScaleAboutAFixedCentre) {
  const Eigen::Vector3d c(1, 2, 3);
  const Similarity3 T = ScaleAbout(c, 1.5);
  EXPECT_TRUE((T * c).isApprox(c));
  EXPECT_TRUE((T * Eigen::Vector3d(3, 2, 3)).isApprox(Eigen::Vector3d(4, 2, 3)));
}

}  // namespace
}  // namespace pectus
