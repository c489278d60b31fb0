// Tests of datasets/chest_landmarks: the eleven landmarks lie exactly on the true skin, in anatomical order.
#include "datasets/chest_landmarks.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "datasets/chest_population.h"
#include "datasets/surface_query.h"
#include "shape/core/error.h"

namespace pectus::datasets {
namespace {

TEST(ChestLandmarks, LieOnTheTrueSurfaceOfEverySubject) {
  for (std::uint64_t seed : {1, 2, 3}) {
    ChestParameters p = SampleSubject(PopulationModel::Default(), seed).parameters;
    p.pectus.depth_mm = 10.0 * static_cast<double>(seed);
    p.T_scan_subject =
        Eigen::Translation3d(5.0 * seed, 0, -40) * Eigen::AngleAxisd(0.2 * seed, Eigen::Vector3d::UnitY());
    const ChestSurface skin(p);
    const LandmarkSet set = TrueLandmarks(skin);
    ASSERT_EQ(set.size(), 11u);
    set.Validate("true landmarks");
    for (const Landmark& l : set.items) {
      // Closest-point distance of the landmark to the analytic surface: 0 to rounding.
      EXPECT_LT(ClosestPoint(skin, l.position).distance, 1e-6) << l.label;
    }
  }
}

TEST(ChestLandmarks, NamesAndAnatomicalOrderInTheChestFrame) {
  const ChestSurface skin(PopulationModel::Default().mean);
  const LandmarkSet set = TrueLandmarks(skin);
  for (const char* label : {"sternal_notch", "manubrium_centre", "sternal_angle", "mid_sternum", "xiphoid",
                            "costal_cartilage_1_left", "costal_cartilage_1_right", "costal_cartilage_4_left",
                            "costal_cartilage_4_right", "costal_margin_left", "costal_margin_right"}) {
    EXPECT_NE(set.Find(label), nullptr) << label;
  }
  const Eigen::Vector3d notch = set.Position("sternal_notch", ""), xiphoid = set.Position("xiphoid", "");
  // The notch is at the origin's height on the midline; the xiphoid one sternal length below.
  EXPECT_NEAR(notch.x(), 0.0, 1e-9);
  EXPECT_NEAR(notch.y(), 0.0, 1e-9);
  EXPECT_NEAR(notch.y() - xiphoid.y(), skin.parameters().sternal_length_mm, 1e-9);
  // Down the sternum in order; left landmarks at +x, mirrored right ones at -x.
  EXPECT_GT(set.Position("manubrium_centre", "").y(), set.Position("sternal_angle", "").y());
  EXPECT_GT(set.Position("sternal_angle", "").y(), set.Position("mid_sternum", "").y());
  EXPECT_GT(set.Position("mid_sternum", "").y(), xiphoid.y());
  for (const char* side : {"costal_cartilage_1_", "costal_cartilage_4_", "costal_margin_"}) {
    const Eigen::Vector3d l = set.Position(std::string(side) + "left", ""),
                          r = set.Position(std::string(side) + "right", "");
    EXPECT_GT(l.x(), 10.0) << side;
    EXPECT_NEAR(l.x(), -r.x(), 1e-9) << side;  // the mean chest is symmetric
    EXPECT_NEAR(l.y(), r.y(), 1e-9) << side;
  }
}

TEST(ChestLandmarks, UnknownLabelIsAUsageError) {
  EXPECT_EQ(FindLandmarkDefinition("xiphoid").label, "xiphoid");
  EXPECT_THROW(FindLandmarkDefinition("navel"), Error);
}

}  // namespace
}  // namespace pectus::datasets
