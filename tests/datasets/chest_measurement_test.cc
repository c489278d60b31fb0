// Tests of datasets/chest_measurement: CT-style width, depth, depression and sternal length of analytic
// chests whose answers are known in closed form.
#include "datasets/chest_measurement.h"

#include <gtest/gtest.h>

#include "datasets/chest_population.h"

namespace pectus::datasets {
namespace {

TEST(ChestMeasurement, NormalChestWallGivesItsParameters) {
  // The chest wall of a chest without a depression is convex across the sternum: no depression, and the slice
  // is the reference level, where the width is W (at the mid-axillary lines) and the depth D (front at D /
  // 2).
  ChestParameters p = SampleSubject(PopulationModel::Default(), 4).parameters;
  const ChestMeasurement m = MeasureChest(ChestSurface(p, Layer::kChestWall));
  EXPECT_LT(m.depression_mm, 1e-3);
  EXPECT_NEAR(m.width_mm, p.width_mm, 1e-6);
  EXPECT_NEAR(m.depth_mm, p.depth_mm, 1e-6);
  EXPECT_NEAR(m.sternal_length_mm, p.sternal_length_mm, 1e-9);
}

TEST(ChestMeasurement, GrowthScalesEveryMeasure) {
  ChestParameters p = PopulationModel::Default().mean;
  p.pectus.depth_mm = 20.0;
  const ChestMeasurement before = MeasureChest(ChestSurface(p, Layer::kChestWall));
  p.growth = Eigen::Vector3d(1.1, 1.2, 1.05);
  const ChestMeasurement after = MeasureChest(ChestSurface(p, Layer::kChestWall));
  // Growth scales x, y and z about the notch: width by 1.1, sternal length by 1.2, depth and depression
  // by 1.05.
  EXPECT_NEAR(after.width_mm, 1.1 * before.width_mm, 1e-3);
  EXPECT_NEAR(after.sternal_length_mm, 1.2 * before.sternal_length_mm, 1e-6);
  EXPECT_NEAR(after.depth_mm, 1.05 * before.depth_mm, 1e-3);
  EXPECT_NEAR(after.depression_mm, 1.05 * before.depression_mm, 1e-3);
}

TEST(ChestMeasurement, DepressionFindsASymmetricSaucerAtItsLevel) {
  // A centred saucer on a flat-fronted region: the measured depression approaches the deformation depth, less
  // the chest's own curvature under the ruler; it lies on the midline at the depression's level.
  ChestParameters p = PopulationModel::Default().mean;
  p.pectus.depth_mm = 30.0;
  p.pectus.centre_y_mm = 10.0;
  const ChestSurface wall(p, Layer::kChestWall);
  const ChestMeasurement m = MeasureChest(wall);
  EXPECT_GT(m.depression_mm, 15.0);
  EXPECT_LT(m.depression_mm, 30.0);
  EXPECT_NEAR(m.deepest_xz.x(), 0.0, 1.0);
  const double centre_y = wall.Position(0.0, kVReference).y() + 10.0;
  EXPECT_NEAR(m.slice_y_mm, centre_y, 3.0);
}

}  // namespace
}  // namespace pectus::datasets
