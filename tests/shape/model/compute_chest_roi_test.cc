// ROI frame: axes from the landmarks, extents, margins, the anterior hint, errors.
#include "shape/model/compute_chest_roi.h"

#include <gtest/gtest.h>

#include "shape/core/error.h"

namespace pectus {
namespace {

// LPS: x toward the left, y posterior, z superior. A subject lying in the scanner frame as in Slicer.
LandmarkSet LpsLandmarks() {
  LandmarkSet s;
  s.items.push_back({"sternal_notch", {10.0, -100.0, 50.0}, ""});
  s.items.push_back({"xiphoid", {10.0, -90.0, -130.0}, ""});  // 180 mm down, 10 mm back
  s.items.push_back({"costal_cartilage_1_left", {55.0, -95.0, 35.0}, ""});
  return s;
}

TEST(ChestRoi, AxesFollowTheLandmarksAndTheNormalIsAnterior) {
  const LandmarkSet l = LpsLandmarks();
  const ChestRoi roi = ComputeChestRoi(l);
  EXPECT_TRUE(roi.origin.isApprox(Eigen::Vector3d(10, -100, 50)));
  EXPECT_TRUE(roi.sternal.isApprox(Eigen::Vector3d(0, 10, -180).normalized(), 1e-12));
  EXPECT_NEAR(roi.lateral.dot(roi.sternal), 0.0, 1e-12);
  EXPECT_NEAR(roi.normal.dot(roi.sternal), 0.0, 1e-12);
  EXPECT_NEAR(roi.normal.dot(roi.lateral), 0.0, 1e-12);
  EXPECT_GT(roi.lateral.x(), 0.9);  // toward the subject's left (+x in LPS)
  EXPECT_LT(roi.normal.y(), -0.9);  // anterior is -y in LPS
  EXPECT_NEAR(roi.v_min, 0.0, 1e-12);
  EXPECT_NEAR(roi.v_max, std::hypot(10.0, 180.0), 1e-9);
  // The cartilage lies in the ROI plane at u = its distance from the sternal line.
  const Points3 c = roi.ToRoi(l.Position("costal_cartilage_1_left", "").transpose());
  EXPECT_NEAR(c(0, 2), 0.0, 1e-9);
  EXPECT_NEAR(roi.u_max, c(0, 0), 1e-9);
  EXPECT_NEAR(roi.u_min, -c(0, 0), 1e-9);
}

TEST(ChestRoi, TransformedIsTheRoiOfTheMovedLandmarks) {
  Similarity3 T;
  T.scale = 1.2;
  T.rotation = Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  T.translation = Eigen::Vector3d(30, -4, 12);
  // The ROI is defined by the landmarks alone, so moving it must give the ROI of the moved landmarks.
  const ChestRoi moved = ComputeChestRoi(LpsLandmarks()).Transformed(T);
  const ChestRoi of_moved = ComputeChestRoi(LpsLandmarks().Transformed(T));
  EXPECT_LT((moved.origin - of_moved.origin).norm(), 1e-9);
  EXPECT_LT((moved.lateral - of_moved.lateral).norm(), 1e-12);
  EXPECT_LT((moved.sternal - of_moved.sternal).norm(), 1e-12);
  EXPECT_LT((moved.normal - of_moved.normal).norm(), 1e-12);
  EXPECT_NEAR(moved.u_min, of_moved.u_min, 1e-9);
  EXPECT_NEAR(moved.u_max, of_moved.u_max, 1e-9);
  EXPECT_NEAR(moved.v_min, of_moved.v_min, 1e-9);
  EXPECT_NEAR(moved.v_max, of_moved.v_max, 1e-9);
}

TEST(ChestRoi, RoundTripOfRoiCoordinates) {
  const ChestRoi roi = ComputeChestRoi(LpsLandmarks());
  Points3 p(3, 3);
  p << 1, 2, 3, -40, 800, 12, 0.5, -0.25, 1e3;
  EXPECT_TRUE(roi.FromRoi(roi.ToRoi(p)).isApprox(p, 1e-12));
  EXPECT_TRUE(roi.FromRoi(1.0, 2.0, 3.0)
                  .isApprox(roi.FromRoi(Points3(Eigen::RowVector3d(1, 2, 3))).row(0).transpose()));
}

TEST(ChestRoi, MarginsWidenTheRectangle) {
  ChestRoiOptions o;
  o.superior_margin_mm = 10;
  o.inferior_margin_mm = 20;
  o.lateral_margin_mm = 5;
  const ChestRoi plain = ComputeChestRoi(LpsLandmarks());
  const ChestRoi wide = ComputeChestRoi(LpsLandmarks(), o);
  EXPECT_NEAR(wide.v_min, -10.0, 1e-12);
  EXPECT_NEAR(wide.v_max, plain.v_max + 20.0, 1e-9);
  EXPECT_NEAR(wide.u_max, plain.u_max + 5.0, 1e-9);
  EXPECT_NEAR(wide.u_min, plain.u_min - 5.0, 1e-9);
}

TEST(ChestRoi, AnteriorHintLevelsTheLateralAxis) {
  ChestRoiOptions o;
  o.anterior_hint = Eigen::Vector3d(0, -1, 0);  // LPS anterior
  const ChestRoi roi = ComputeChestRoi(LpsLandmarks(), o);
  // Lateral is perpendicular to the sternal line and to the hint: here exactly +x.
  EXPECT_TRUE(roi.lateral.isApprox(Eigen::Vector3d::UnitX(), 1e-12));
  EXPECT_NEAR(roi.u_max, 45.0, 1e-9);  // the cartilage's x offset from the notch
  EXPECT_LT(roi.normal.y(), -0.99);
}

TEST(ChestRoi, MissingOrDegenerateLandmarksAreBadInput) {
  LandmarkSet l = LpsLandmarks();
  l.items.pop_back();
  EXPECT_THROW(ComputeChestRoi(l, {}, "a.mrk.json"), Error);
  LandmarkSet on_line = LpsLandmarks();
  on_line.items[2].position = Eigen::Vector3d(10.0, -95.0, -40.0);  // on the sternal line
  try {
    ComputeChestRoi(on_line, {}, "b.mrk.json");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kBadInput);
    EXPECT_NE(std::string(e.what()).find("b.mrk.json"), std::string::npos);
  }
  ChestRoiOptions bad;
  bad.lateral_margin_mm = -1;
  EXPECT_FALSE(bad.IsValid(nullptr));
}

}  // namespace
}  // namespace pectus
