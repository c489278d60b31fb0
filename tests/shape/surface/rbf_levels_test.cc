#include "shape/surface/rbf_levels.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

namespace pectus {
namespace {

Points3 Rows(const std::vector<Eigen::Vector3d>& p) {
  Points3 m(Eigen::Index(p.size()), 3);
  for (std::size_t i = 0; i < p.size(); ++i) m.row(Eigen::Index(i)) = p[i].transpose();
  return m;
}

// The row of `level` nearest to x, and its distance.
Eigen::Index NearestRow(const RbfLevel& level, const Eigen::Vector3d& x, double* distance) {
  std::uint32_t k = 0;
  double d2 = 0.0;
  level.tree->Nearest(x, &k, &d2);
  *distance = std::sqrt(d2);
  return Eigen::Index(k);
}

// Cubes of side 2 mm from the bounds' corner (0, 0, 0), the averages found by hand.
TEST(AverageByVoxel, AveragesThePointsOfEachCubeWithTheirCounts) {
  std::vector<Eigen::Vector3d> p = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(5.9, 2.0, 2.0)};
  for (int s = 0; s < 8; ++s)
    p.push_back(Eigen::Vector3d(1, 1, 1) +
                0.5 * Eigen::Vector3d(s & 1 ? 1 : -1, s & 2 ? 1 : -1, s & 4 ? 1 : -1));
  for (int s = 0; s < 4; ++s)
    p.push_back(Eigen::Vector3d(5, 1, 1) + 0.5 * Eigen::Vector3d(s & 1 ? 1 : -1, 0, s & 2 ? 1 : -1));
  const Points3 positions = Rows(p);
  Eigen::VectorXd counts = Eigen::VectorXd::Ones(positions.rows());
  counts(0) = 3.0;  // the corner point stands for three input points
  RbfLevel level;
  AverageByVoxel(positions, Points3(0, 3), counts, 2.0, &level);

  EXPECT_EQ(level.spacing, 2.0);
  EXPECT_EQ(level.normals.rows(), 0) << "no normals in, none out";
  // Cubes: (0,0,0) holds the corner point and the eight around (1,1,1); (2,0,0) holds the four around
  // (5,1,1); (2,1,1) holds (5.9,2,2). The corner point (count 3) pulls its cube's mean toward it.
  ASSERT_EQ(level.positions.rows(), 3);
  ASSERT_EQ(level.counts.size(), 3);
  double d = 0.0;
  Eigen::Index r = NearestRow(level, Eigen::Vector3d(8.0 / 11.0, 8.0 / 11.0, 8.0 / 11.0), &d);
  EXPECT_LT(d, 1e-12);  // (3 * 0 + 8 * 1) / 11 on every axis
  EXPECT_EQ(level.counts(r), 11.0);
  r = NearestRow(level, Eigen::Vector3d(5, 1, 1), &d);
  EXPECT_LT(d, 1e-12);
  EXPECT_EQ(level.counts(r), 4.0);
  r = NearestRow(level, Eigen::Vector3d(5.9, 2, 2), &d);
  EXPECT_LT(d, 1e-12);
  EXPECT_EQ(level.counts(r), 1.0);
  EXPECT_EQ(level.counts.sum(), counts.sum()) << "every input point is in exactly one average";
}

// A thin sheet: in one cube, points with normal +z and points with normal -z are averaged apart, each side
// with its own mean position and unit normal.
TEST(AverageByVoxel, KeepsTheTwoSidesOfAThinSheetApart) {
  const Points3 positions = Rows({Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(0.5, 0.0, 0.0),
                                  Eigen::Vector3d(0.0, 0.0, 0.4), Eigen::Vector3d(0.5, 0.5, 0.4)});
  const Eigen::Vector3d tilt = Eigen::Vector3d(0.1, 0.0, 1.0).normalized();
  const Points3 normals =
      Rows({Eigen::Vector3d::UnitZ(), tilt, -Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitZ()});
  RbfLevel level;
  AverageByVoxel(positions, normals, Eigen::VectorXd::Ones(4), 1.0, &level);
  ASSERT_EQ(level.positions.rows(), 2);
  ASSERT_EQ(level.normals.rows(), 2);
  double d = 0.0;
  const Eigen::Index up = NearestRow(level, Eigen::Vector3d(0.25, 0.0, 0.0), &d);
  EXPECT_LT(d, 1e-12);
  EXPECT_EQ(level.counts(up), 2.0);
  EXPECT_LT((level.normals.row(up).transpose() - (Eigen::Vector3d::UnitZ() + tilt).normalized()).norm(),
            1e-12);
  const Eigen::Index down = NearestRow(level, Eigen::Vector3d(0.25, 0.25, 0.4), &d);
  EXPECT_LT(d, 1e-12);
  EXPECT_EQ(level.counts(down), 2.0);
  EXPECT_LT((level.normals.row(down).transpose() + Eigen::Vector3d::UnitZ()).norm(), 1e-12);
}

// The plane z = 0 sampled 0.5 mm apart over [-10, 10]^2, and a level of one point at the origin with
// normal +z, whose off-surface points are sought at eps = 2 mm.
class OffSurface : public ::testing::Test {
 protected:
  void SetFine(std::vector<Eigen::Vector3d> extra) {
    for (double x = -10.0; x <= 10.0 + 1e-9; x += 0.5)
      for (double y = -10.0; y <= 10.0 + 1e-9; y += 0.5) extra.emplace_back(x, y, 0.0);
    fine_.positions = Rows(extra);
    fine_.tree = std::make_unique<KdTree3>(fine_.positions);
    level_.positions = Rows({Eigen::Vector3d::Zero()});
    level_.normals = Rows({Eigen::Vector3d::UnitZ()});
    level_.counts = Eigen::VectorXd::Ones(1);
  }
  RbfLevel fine_, level_;
};

TEST_F(OffSurface, AFreeSideKeepsTheFullDistance) {
  SetFine({});
  SetOffSurfaceDistances(fine_, 2.0, &level_);
  EXPECT_EQ(level_.eps_plus(0), 2.0);
  EXPECT_EQ(level_.eps_minus(0), 2.0);
}

TEST_F(OffSurface, ASheetAboveHalvesTheDistanceOnThatSideOnly) {
  // A sheet at z = 1: (0,0,2) is 1 mm from it (< 0.7 * 2), (0,0,1) on it, (0,0,0.5) 0.5 mm from it
  // (>= 0.7 * 0.5): eps = 0.5 on the + side; the - side is free.
  std::vector<Eigen::Vector3d> sheet;
  for (double x = -10.0; x <= 10.0 + 1e-9; x += 0.5)
    for (double y = -10.0; y <= 10.0 + 1e-9; y += 0.5) sheet.emplace_back(x, y, 1.0);
  SetFine(sheet);
  SetOffSurfaceDistances(fine_, 2.0, &level_);
  EXPECT_EQ(level_.eps_plus(0), 0.5);
  EXPECT_EQ(level_.eps_minus(0), 2.0);
}

TEST_F(OffSurface, NoFreePointAfterThreeHalvingsGivesNoConstraint) {
  // Data at every point tried on the - side (2, 1, 0.5 and 0.25 mm below): no off-surface point there.
  SetFine({Eigen::Vector3d(0, 0, -2), Eigen::Vector3d(0, 0, -1), Eigen::Vector3d(0, 0, -0.5),
           Eigen::Vector3d(0, 0, -0.25)});
  SetOffSurfaceDistances(fine_, 2.0, &level_);
  EXPECT_EQ(level_.eps_plus(0), 2.0);
  EXPECT_EQ(level_.eps_minus(0), 0.0);
}

TEST(WendlandC2, KnownValues) {
  EXPECT_EQ(WendlandC2(0.0), 1.0);
  EXPECT_DOUBLE_EQ(WendlandC2(0.5), 0.0625 * 3.0);  // (1 - r)^4 (4 r + 1)
  EXPECT_EQ(WendlandC2(1.0), 0.0);
  EXPECT_EQ(WendlandC2(2.5), 0.0);
}

// One cell: two on-surface rows and two centres, one with off-surface points on both sides, one with
// none below (eps_minus = 0), and a third centre outside the ball (weight 0): the problem holds exactly
// the constraints with weight, each with its value and weight.
TEST(LocalProblem, HoldsTheWeightedConstraintsOfTheCell) {
  RbfLevel rows_level;
  rows_level.positions = Rows({Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 2, 0)});
  rows_level.counts = Eigen::Vector2d(2.0, 5.0);
  RbfLevel centres_level;
  centres_level.positions =
      Rows({Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 0, 3), Eigen::Vector3d(9, 0, 0)});
  centres_level.normals =
      Rows({Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ()});
  centres_level.counts = Eigen::Vector3d(1.0, 4.0, 1.0);
  centres_level.eps_plus = Eigen::Vector3d(0.5, 0.25, 0.5);
  centres_level.eps_minus = Eigen::Vector3d(0.5, 0.0, 0.5);
  const Eigen::Vector3d origin(0, 0, 0);
  const double radius = 4.0;
  const LevelNeighbours rows = {{0, 1.0}, {1, 4.0}};                // squared distances to origin
  const LevelNeighbours centres = {{0, 0.0}, {1, 9.0}, {2, 81.0}};  // the third is beyond the radius
  const LocalRbfProblem problem =
      LocalProblem(rows_level, rows, centres_level, centres, origin, radius, 10.0);

  EXPECT_EQ(problem.origin, origin);
  EXPECT_EQ(problem.scale, radius);
  ASSERT_EQ(problem.centres.rows(), 3);
  EXPECT_EQ(problem.centres.row(1), centres_level.positions.row(1));
  // 2 on-surface rows, 2 off-surface points of centre 0, 1 of centre 1, none of centre 2.
  ASSERT_EQ(problem.points.rows(), 5);
  ASSERT_EQ(problem.values.size(), 5);
  ASSERT_EQ(problem.weights.size(), 5);
  const Eigen::VectorXd values = (Eigen::VectorXd(5) << 0.0, 0.0, 0.5, -0.5, 0.25).finished();
  EXPECT_EQ(problem.values, values);
  EXPECT_DOUBLE_EQ(problem.weights(0), 2.0 * WendlandC2(1.0 / 4.0));
  EXPECT_DOUBLE_EQ(problem.weights(1), 5.0 * WendlandC2(2.0 / 4.0));
  EXPECT_DOUBLE_EQ(problem.weights(2), 10.0 * 1.0 * WendlandC2(0.0));
  EXPECT_DOUBLE_EQ(problem.weights(3), 10.0 * 1.0 * WendlandC2(0.0));
  EXPECT_DOUBLE_EQ(problem.weights(4), 10.0 * 4.0 * WendlandC2(3.0 / 4.0));
  EXPECT_EQ(problem.points.row(2), Eigen::RowVector3d(0, 0, 0.5));
  EXPECT_EQ(problem.points.row(3), Eigen::RowVector3d(0, 0, -0.5));
  EXPECT_EQ(problem.points.row(4), Eigen::RowVector3d(0.25, 0, 3));
}

}  // namespace
}  // namespace pectus
