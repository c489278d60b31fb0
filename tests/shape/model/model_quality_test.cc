// Compactness, generalization and specificity (Styner et al. 2003) on the hand-checked four-subject
// example of shape_model_test.cc: x1,2 = (+-3, 0, 0), x3,4 = (0, +-1, 0).
#include "shape/model/model_quality.h"

#include <gtest/gtest.h>

#include "shape/core/error.h"
#include "toy_shapes.h"

namespace pectus {
namespace {

TEST(ModelQuality, CompactnessIsTheCumulativeVariance) {
  const ModelQualityCurves q = EvaluateModelQuality(testing::ToyShapes());
  ASSERT_EQ(q.modes.size(), 3);  // M = 0, 1, 2 (a leave-one-out model has N - 2 = 2 modes)
  EXPECT_NEAR(q.compactness[0], 0.0, 1e-12);
  EXPECT_NEAR(q.compactness[1], 6.0, 1e-12);
  EXPECT_NEAR(q.compactness[2], 6.0 + 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(q.compactness_sd[1], std::sqrt(2.0 / 4.0) * 6.0, 1e-12);
}

TEST(ModelQuality, GeneralizationByHand) {
  // Leaving out x1: mean (-1, 0, 0), modes x (variance 3) then y (variance 1); x1 - mean = (4, 0, 0) is
  // all in mode 1: errors 4, 0, 0 for M = 0, 1, 2. Same for x2. Leaving out x3: mean (0, -1/3, 0), mode 1
  // is x (variance 9), x3 - mean = (0, 4/3, 0): errors 4/3, 4/3, 0. Same for x4.
  // G(0) = (4 + 4 + 4/3 + 4/3) / 4 = 8/3, G(1) = (4/3 + 4/3) / 4 = 2/3, G(2) = 0.
  const ModelQualityCurves q = EvaluateModelQuality(testing::ToyShapes());
  EXPECT_NEAR(q.generalization_mm[0], 8.0 / 3.0, 1e-12);
  EXPECT_NEAR(q.generalization_mm[1], 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(q.generalization_mm[2], 0.0, 1e-12);
  // Standard error for M = 1: terms (0, 0, 4/3, 4/3), sample sd = sqrt(4 (2/3)^2 / 3), / sqrt(3).
  EXPECT_NEAR(q.generalization_sd[1], std::sqrt(4.0 * 4.0 / 9.0 / 3.0) / std::sqrt(3.0), 1e-12);
}

TEST(ModelQuality, SpecificityByHand) {
  const ShapeModel m = BuildShapeModel(testing::ToyShapes());
  // M = 0: every sample is the mean (0, 0, 0); the nearest training shape is x3 or x4 at distance 1.
  Eigen::MatrixXd b(2, 2);
  b << 1.0, 0.0, -0.5, 2.0;
  double sd = -1.0;
  EXPECT_NEAR(Specificity(m, testing::ToyShapes(), b, 0, &sd), 1.0, 1e-12);
  EXPECT_NEAR(sd, 0.0, 1e-12);
  // M = 1: samples (sqrt 6, 0, 0) and (-sqrt(6)/2, 0, 0); nearest x1 at 3 - sqrt 6, and x3 (0, 1, 0) at
  // sqrt(6/4 + 1) (x2 is 3 - sqrt(6)/2 = 1.78 away).
  const double d1 = 3.0 - std::sqrt(6.0), d2 = std::sqrt(2.5);
  EXPECT_NEAR(Specificity(m, testing::ToyShapes(), b, 1, &sd), 0.5 * (d1 + d2), 1e-12);
  EXPECT_NEAR(sd, std::abs(d1 - d2) / std::sqrt(2.0) / 1.0, 1e-12);
  // M = 2: the second sample moves 2 sd (2 sqrt(2/3)) along y: (-sqrt(6)/2, 1.633, 0); nearest is x3.
  const Eigen::Vector3d y2(-std::sqrt(6.0) / 2.0, 2.0 * std::sqrt(2.0 / 3.0), 0.0);
  const double d3 = std::min((y2 - Eigen::Vector3d(0, 1, 0)).norm(), (y2 - Eigen::Vector3d(-3, 0, 0)).norm());
  EXPECT_NEAR(Specificity(m, testing::ToyShapes(), b, 2), 0.5 * (d1 + d3), 1e-12);
}

TEST(ModelQuality, RandomSpecificityIsReproducibleAndCurvesHaveTheirShapes) {
  ModelQualityOptions o;
  o.specificity_samples = 50;
  const ModelQualityCurves a = EvaluateModelQuality(testing::ToyShapes(), o),
                           b = EvaluateModelQuality(testing::ToyShapes(), o);
  EXPECT_TRUE(a.specificity_mm.isApprox(b.specificity_mm));
  EXPECT_NEAR(a.specificity_mm[0], 1.0, 1e-12);
  EXPECT_THROW(EvaluateModelQuality(testing::ToyShapes().topRows(2)), Error);
  o.specificity_samples = 0;
  EXPECT_THROW(EvaluateModelQuality(testing::ToyShapes(), o), Error);
}

TEST(ModelQuality, MeanVertexDistanceAveragesPerVertex) {
  Eigen::VectorXd a = Eigen::VectorXd::Zero(6), b(6);
  b << 3, 4, 0, 0, 0, 1;  // vertex distances 5 and 1
  EXPECT_NEAR(MeanVertexDistance(a, b), 3.0, 1e-12);
}

}  // namespace
}  // namespace pectus
