// The sternal bone's skinning on a straight vertical sternum, where the bone's motion and every weight
// have closed forms: the hinge about the sternal angle, the torsion about the axis, the envelopes' fall-offs
// (a quarter sine across the chest, steepest at the sternum's edge; smootherstep along and behind), and
// points of full weight moving rigidly with the bone.
#include "planner_plugin/ribcage/sternum_skinning.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <vector>

#include "shape/core/error.h"

namespace pectus::planner {
namespace {

// The axis from the notch (0, 0, 100) straight down to the tip (0, 0, 0), half-width 10 mm; the weight
// rises along it from fraction 0.2 (z = 80, the hinge) to 0.4 (z = 60). The reference point (fraction
// 0.85) is (0, 0, 15), 65 mm below the hinge.
SternumSkinning StraightSternum(double scale = 1.0) {
  Points3 axis(11, 3);
  for (int i = 0; i <= 10; ++i) axis.row(i) << 0.0, 0.0, 100.0 - 10.0 * i;
  return SternumSkinning(axis, std::vector<double>(11, 10.0), 0.2, 0.4, scale, SternumSkinningOptions{});
}

const Eigen::Vector3d kHinge(0, 0, 80);

// The bone's rigid motion in closed form: hinged back by asin(depression / 65) about +x through the
// hinge (which moves the reference point 65 mm below it `depression` posteriorly), then turned by the
// torsion about the hinged axis (the axis points down, -z, before the hinge).
Eigen::Vector3d Bone(const Eigen::Vector3d& p, double depression_mm, double torsion_rad) {
  const Eigen::Matrix3d hinge =
      Eigen::AngleAxisd(std::asin(depression_mm / 65.0), Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Matrix3d twist =
      Eigen::AngleAxisd(torsion_rad, hinge * -Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return twist * hinge * (p - kHinge) + kHinge;
}

// smootherstep(t) = 6t^5 - 15t^4 + 10t^3 is 1/2 at t = 1/2, and smoothstep too: the middle of the
// envelopes along and behind gives a weight of 1/2 exactly; across, 1 - sin(pi t / 2) is 1/2 at t = 1/3.
TEST(SternumSkinning, WeightsFollowTheEnvelopesInClosedForm) {
  const SternumSkinning s = StraightSternum();
  // Full weight on the lower sternum (up to its edge, 10 mm from the axis, and 30 mm behind it); none
  // above the second cartilage's joint, beyond 85 mm from the edge, or 70 mm behind the axis.
  EXPECT_EQ(s.Weight({0, 0, 30}), 1.0);
  EXPECT_EQ(s.Weight({9.9, -5, 30}), 1.0);
  EXPECT_EQ(s.Weight({-10, 29.9, 50}), 1.0);
  EXPECT_EQ(s.Weight({0, 0, 85}), 0.0);
  EXPECT_EQ(s.Weight({95.1, 0, 30}), 0.0);
  EXPECT_EQ(s.Weight({0, 70.1, 30}), 0.0);
  // Across the chest the weight is 1 - sin(pi t / 2), t the distance beyond the edge over 85 mm: it falls
  // at once beside the sternum (a saucer: the chest wall rises from the sternum's depth), to 1/2 a third
  // of the way (28.3 mm beyond the edge), the same below the tip.
  EXPECT_NEAR(s.Weight({11, 0, 30}), 1.0 - std::sin(M_PI / 170.0), 1e-12);
  EXPECT_LT(s.Weight({11, 0, 30}), 0.99);
  const double third = 85.0 / 3.0;
  EXPECT_NEAR(s.Weight({10 + third, 0, 30}), 0.5, 1e-12);
  EXPECT_NEAR(s.Weight({-10 - third, 0, 30}), 0.5, 1e-12);
  EXPECT_NEAR(s.Weight({0, 0, -third}), 0.5, 1e-12);
  // Along (z = 70, halfway from the hinge to full weight) and behind (50 mm): smootherstep's middles.
  EXPECT_NEAR(s.Weight({0, 0, 70}), 0.5, 1e-12);
  EXPECT_NEAR(s.Weight({0, 50, 30}), 0.5, 1e-12);
  EXPECT_NEAR(s.Weight({10 + third, 50, 70}), 0.125, 1e-12);  // their product
  // The envelopes scale with the ribcage: twice as wide a ribcage, twice the distances.
  EXPECT_NEAR(StraightSternum(2.0).Weight({10 + 2 * third, 0, 30}), 0.5, 1e-12);
  // Weights lie in [0, 1] everywhere.
  for (double x = -120; x <= 120; x += 7.5) {
    for (double y = -40; y <= 90; y += 6.5) {
      for (double z = -120; z <= 120; z += 9.5) {
        const double w = s.Weight({x, y, z});
        ASSERT_GE(w, 0.0);
        ASSERT_LE(w, 1.0);
      }
    }
  }
}

TEST(SternumSkinning, HingeMovesTheReferencePointByTheDepression) {
  const SternumSkinning s = StraightSternum();
  for (double d : {0.0, 5.0, 21.0, 40.0}) {
    EXPECT_NEAR(s.HingeAngle(d), std::asin(d / 65.0), 1e-12) << d;
    const Eigen::Vector3d reference(0, 0, 15);
    const Eigen::Vector3d moved = s.Apply(reference, d, 0.0);
    EXPECT_NEAR(moved.y() - reference.y(), d, 1e-9) << d;
    EXPECT_NEAR(moved.z() - reference.z(), 65.0 * (1 - std::cos(std::asin(d / 65.0))), 1e-9) << d;
  }
}

TEST(SternumSkinning, PointsOfFullWeightMoveRigidlyWithTheBone) {
  const SternumSkinning s = StraightSternum();
  const double depression = 21.0, torsion = 0.2;
  // Points of weight 1 (the lower sternum) move by the bone's rigid motion.
  const std::vector<Eigen::Vector3d> points = {
      {0, 0, 50}, {-10, -5, 40}, {8, 20, 10}, {0, 10, 0}, {-5, 0, 2}};
  for (const Eigen::Vector3d& p : points) {
    ASSERT_EQ(s.Weight(p), 1.0);
    EXPECT_LT((s.Apply(p, depression, torsion) - Bone(p, depression, torsion)).norm(), 1e-9) << p.transpose();
  }
  // So distances between them are kept.
  for (const Eigen::Vector3d& p : points) {
    for (const Eigen::Vector3d& q : points) {
      EXPECT_NEAR((s.Apply(p, depression, torsion) - s.Apply(q, depression, torsion)).norm(), (p - q).norm(),
                  1e-9);
    }
  }
  // Torsion alone turns the right edge (x < 0) posterior about the axis: (-10, 0) to (-10 cos, 10 sin).
  const Eigen::Vector3d edge(-10, 0, 30);
  EXPECT_LT(
      (s.Apply(edge, 0.0, torsion) - Eigen::Vector3d(-10 * std::cos(torsion), 10 * std::sin(torsion), 30))
          .norm(),
      1e-9);
}

TEST(SternumSkinning, EveryPointBlendsTheBoneAndTheRestByItsWeight) {
  // p + w (B(p) - p): the bone's share w and the resting ribcage's share 1 - w sum to one, so points of
  // weight 0 stay, and a point of weight 1/2 goes halfway.
  const SternumSkinning s = StraightSternum();
  const double depression = 21.0, torsion = -0.15;
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(57.5, 0, 30), Eigen::Vector3d(57.5, 50, 70),
                                   Eigen::Vector3d(30, 40, 65), Eigen::Vector3d(-70, 10, -20)}) {
    const double w = s.Weight(p);
    EXPECT_LT((s.Apply(p, depression, torsion) - (p + w * (Bone(p, depression, torsion) - p))).norm(), 1e-9)
        << p.transpose() << " weight " << w;
  }
  for (const Eigen::Vector3d& p :
       {Eigen::Vector3d(0, 0, 90), Eigen::Vector3d(100, 0, 30), Eigen::Vector3d(0, 80, 30)}) {
    ASSERT_EQ(s.Weight(p), 0.0);
    EXPECT_EQ(s.Apply(p, depression, torsion), p);
  }
  // No depression and no torsion: nothing moves.
  EXPECT_LT((s.Apply({5, 5, 20}, 0.0, 0.0) - Eigen::Vector3d(5, 5, 20)).norm(), 1e-12);
}

TEST(SternumSkinning, BadAxesAndEnvelopesAreRefused) {
  Points3 one(1, 3);
  one << 0, 0, 0;
  EXPECT_THROW(SternumSkinning(one, {10.0}, 0.2, 0.4, 1.0, {}), Error);
  Points3 axis(2, 3);
  axis << 0, 0, 100, 0, 0, 0;
  EXPECT_THROW(SternumSkinning(axis, {10.0}, 0.2, 0.4, 1.0, {}), Error);        // one half-width short
  EXPECT_THROW(SternumSkinning(axis, {10.0, 10.0}, 0.4, 0.2, 1.0, {}), Error);  // ramp backwards
  SternumSkinningOptions inverted;
  inverted.inner_envelope_mm = 10.0;
  inverted.outer_envelope_mm = 5.0;  // inside the inner envelope
  EXPECT_THROW(SternumSkinning(axis, {10.0, 10.0}, 0.2, 0.4, 1.0, inverted), Error);
}

}  // namespace
}  // namespace pectus::planner
