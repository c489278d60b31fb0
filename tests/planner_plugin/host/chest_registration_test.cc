#include "planner_plugin/host/chest_registration.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "shape/core/error.h"

namespace pectus::planner {
namespace {

LandmarkSet Midline() {
  LandmarkSet set;
  set.items.push_back({"sternal_notch", Eigen::Vector3d(0, 0, 0), ""});
  set.items.push_back({"manubrium_centre", Eigen::Vector3d(0, -3, -25), ""});
  set.items.push_back({"xiphoid", Eigen::Vector3d(0, -40, -150), ""});
  set.items.push_back({"xiphoid_tip", Eigen::Vector3d(0, -42, -170), ""});  // not in the default labels
  return set;
}

Similarity3 KnownTransform(double scale) {
  Similarity3 T;
  T.scale = scale;
  T.rotation = (Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()) *
                Eigen::AngleAxisd(-1.2, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation = Eigen::Vector3d(120, -35, 900);
  return T;
}

// Three midline landmarks leave the roll about the sternal line free: the anterior directions fix it,
// and the known transform comes back exactly, in both directions.
TEST(ChestRegistration, RecoversAKnownSimilarityFromMidlineLandmarksAndTheAnteriorDirection) {
  const LandmarkSet source = Midline();
  const Eigen::Vector3d anterior(0, -1, 0);  // LPS: anterior is -y
  for (double scale : {1.0, 1.15, 0.8}) {
    const Similarity3 T = KnownTransform(scale);
    const ChestRegistrationResult r =
        RegisterChestByLandmarks(source, anterior, source.Transformed(T), T.rotation * anterior);
    EXPECT_NEAR(r.T_target_source.scale, scale, 1e-12);
    EXPECT_LT((r.T_target_source.rotation - T.rotation).norm(), 1e-12);
    EXPECT_LT((r.T_target_source.translation - T.translation).norm(), 1e-9);
    EXPECT_LT(r.landmark_rms_mm, 1e-9);
    EXPECT_EQ(r.used, (std::vector<std::string>{"sternal_notch", "manubrium_centre", "xiphoid"}));
    const ChestRegistrationResult back =
        RegisterChestByLandmarks(source.Transformed(T), T.rotation * anterior, source, anterior);
    EXPECT_NEAR(back.T_target_source.scale, 1.0 / scale, 1e-12);
  }
}

TEST(ChestRegistration, RigidKeepsTheScaleAndTheAnteriorNeedNotBeExact) {
  const LandmarkSet source = Midline();
  const Similarity3 T = KnownTransform(1.2);
  ChestRegistrationOptions rigid;
  rigid.similarity = false;
  // An anterior direction tilted along the sternal line changes nothing: only its part across the
  // sternal line counts.
  const Eigen::Vector3d sternal =
      (source.Position("xiphoid", "") - source.Position("sternal_notch", "")).normalized();
  const ChestRegistrationResult r =
      RegisterChestByLandmarks(source, Eigen::Vector3d(0, -1, 0) + 0.5 * sternal, source.Transformed(T),
                               T.rotation * Eigen::Vector3d(0, -1, 0), rigid);
  EXPECT_EQ(r.T_target_source.scale, 1.0);
  EXPECT_LT((r.T_target_source.rotation - T.rotation).norm(), 1e-12);
  EXPECT_GT(r.landmark_rms_mm, 1.0);  // a rigid fit cannot absorb a 20 % size difference
}

TEST(ChestRegistration, RefusesMissingLandmarksAndAnUnusableAnterior) {
  LandmarkSet source = Midline();
  LandmarkSet no_xiphoid = source;
  no_xiphoid.items.erase(no_xiphoid.items.begin() + 2);
  EXPECT_THROW(RegisterChestByLandmarks(no_xiphoid, {0, -1, 0}, source, {0, -1, 0}), Error);
  const Eigen::Vector3d along = source.Position("xiphoid", "") - source.Position("sternal_notch", "");
  EXPECT_THROW(RegisterChestByLandmarks(source, along, source, {0, -1, 0}), Error);
  TriangleMesh flat;
  flat.vertices.positions = Points3::Zero(3, 3);
  flat.faces = Faces3::Zero(1, 3);
  flat.faces << 0, 1, 2;
  EXPECT_THROW(AnteriorDirection(flat, "flat"), Error);
}

}  // namespace
}  // namespace pectus::planner
