// How far apart two estimates of one transform are (ComparePoses, RmsDisplacement), and the common motion
// between two placements of the same point sets (BestCommonMotion), against transforms built by hand.
#include "registration/pose_error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "shape/core/error.h"
#include "tests/support/poses.h"

namespace pectus {
namespace {

using testing_support::AxisAnglePose;

// Three strips of 200 random points, 100 mm long, in their own frames.
std::vector<PointCloud> Strips() {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<PointCloud> sets(3);
  for (PointCloud& c : sets) {
    c.positions.resize(200, 3);
    for (Eigen::Index i = 0; i < 200; ++i) c.positions.row(i) << 100.0 * u(rng), 20.0 * u(rng), u(rng);
  }
  return sets;
}

TEST(PoseError, ComparesRotationAndTranslationAtThePointGiven) {
  const Similarity3 truth =
      Similarity3::FromRigid(AxisAnglePose(0.0, Eigen::Vector3d::UnitZ(), Eigen::Vector3d(1, 2, 3)));
  const Similarity3 estimate =
      Similarity3::FromRigid(AxisAnglePose(2.0, Eigen::Vector3d::UnitZ(), Eigen::Vector3d(1, 2, 3)));
  const Eigen::Vector3d at(100.0, 0.0, 0.0);
  const PoseError e = ComparePoses(estimate, truth, at);
  EXPECT_NEAR(e.rotation_deg, 2.0, 1e-12);
  // A 2 degree turn about the origin moves a point 100 mm away by 2 * 100 * sin(1 degree).
  EXPECT_NEAR(e.translation_mm, 200.0 * std::sin(M_PI / 180.0), 1e-9);
  EXPECT_DOUBLE_EQ(e.scale_ratio, 1.0);
}

TEST(PoseError, RmsDisplacementOfATranslationIsItsLength) {
  const Points3 p = Strips()[0].positions;
  const Similarity3 a =
      Similarity3::FromRigid(AxisAnglePose(0.0, Eigen::Vector3d::UnitX(), Eigen::Vector3d(3, 4, 0)));
  EXPECT_NEAR(RmsDisplacement(p, a, Similarity3()), 5.0, 1e-12);
  EXPECT_NEAR(RmsDisplacement(p, a, a), 0.0, 1e-12);
}

TEST(BestCommonMotion, RecoversTheMotionBetweenTwoPlacements) {
  const std::vector<PointCloud> sets = Strips();
  const std::vector<Rigid3> truth = {
      AxisAnglePose(0.0, Eigen::Vector3d::UnitX(), Eigen::Vector3d(0, 0, 0)),
      AxisAnglePose(20.0, Eigen::Vector3d::UnitY(), Eigen::Vector3d(90, 0, 10)),
      AxisAnglePose(-35.0, Eigen::Vector3d(1, 1, 0), Eigen::Vector3d(0, 80, -5))};
  // The same alignment seen from another frame: G maps `placed` onto `truth` exactly.
  const Rigid3 G = AxisAnglePose(7.0, Eigen::Vector3d(0.3, -1.0, 0.5), Eigen::Vector3d(-12.0, 4.0, 250.0));
  std::vector<Rigid3> placed;
  for (const Rigid3& T : truth) placed.push_back(G.inverse() * T);
  for (Eigen::Index stride : {1, 10}) {
    const Rigid3 found = BestCommonMotion(sets, placed, truth, stride);
    EXPECT_LT((found.matrix() - G.matrix()).cwiseAbs().maxCoeff(), 1e-9) << "stride " << stride;
  }
  // One set moved 1 mm along z on top: no motion maps all sets exactly; the one found is the least-squares
  // optimum: better than G, and than itself nudged by 0.01 mm or 0.01 degrees along any of the six axes.
  std::vector<Rigid3> moved = placed;
  moved[1] = AxisAnglePose(0.0, Eigen::Vector3d::UnitX(), Eigen::Vector3d(0, 0, 1)) * moved[1];
  const auto cost = [&](const Rigid3& M) {
    double sum = 0.0;
    for (std::size_t s = 0; s < sets.size(); ++s) {
      for (Eigen::Index i = 0; i < sets[s].size(); ++i) {
        const Eigen::Vector3d x = sets[s].positions.row(i).transpose();
        sum += (M * moved[s] * x - truth[s] * x).squaredNorm();
      }
    }
    return sum;
  };
  const Rigid3 found = BestCommonMotion(sets, moved, truth);
  const double best = cost(found);
  EXPECT_LT(best, cost(G));
  for (int axis = 0; axis < 3; ++axis) {
    for (double sign : {-1.0, 1.0}) {
      const Eigen::Vector3d e = sign * Eigen::Vector3d::Unit(axis);
      EXPECT_GT(cost(AxisAnglePose(0.0, Eigen::Vector3d::UnitX(), 0.01 * e) * found), best)
          << "shift " << axis;
      EXPECT_GT(cost(AxisAnglePose(0.01, e, Eigen::Vector3d::Zero()) * found), best) << "turn " << axis;
    }
  }
}

TEST(BestCommonMotion, RefusesSizesThatDisagree) {
  const std::vector<PointCloud> sets = Strips();
  const std::vector<Rigid3> two(2, Rigid3::Identity()), three(3, Rigid3::Identity());
  EXPECT_THROW(BestCommonMotion(sets, two, three), Error);
  EXPECT_THROW(BestCommonMotion(sets, three, three, 0), Error);
  EXPECT_THROW(BestCommonMotion({}, {}, {}), Error);
}

}  // namespace
}  // namespace pectus
