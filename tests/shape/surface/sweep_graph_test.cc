#include "shape/surface/sweep_graph.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <set>
#include <utility>
#include <vector>

#include "shape/core/geometry.h"

namespace pectus {
namespace {

constexpr double kRadiusMm = 50.0;
// A sector of the cylinder x^2 + z^2 = 50^2 (axis y), angles [from, to] degrees from +z toward +x and
// y in [y0, y0 + 40] mm, sampled about 1 mm apart, stored in the sweep's own frame: the world points
// moved by T_world_sweep^-1.
PointCloud Sector(double from_deg, double to_deg, double y0, const Rigid3& T_world_sweep) {
  const double step = 1.0 / kRadiusMm;  // 1 mm of arc
  std::vector<Eigen::Vector3d> p;
  for (double a = from_deg * kDegree; a <= to_deg * kDegree + 1e-9; a += step)
    for (double y = y0; y <= y0 + 40.0 + 1e-9; y += 1.0)
      p.push_back(T_world_sweep.inverse() *
                  Eigen::Vector3d(kRadiusMm * std::sin(a), y, kRadiusMm * std::cos(a)));
  PointCloud c;
  c.positions.resize(Eigen::Index(p.size()), 3);
  for (std::size_t i = 0; i < p.size(); ++i) c.positions.row(Eigen::Index(i)) = p[i].transpose();
  return c;
}

Rigid3 Pose(double angle_deg, const Eigen::Vector3d& axis, const Eigen::Vector3d& t) {
  Rigid3 T = Rigid3::Identity();
  T.linear() = Eigen::AngleAxisd(angle_deg * kDegree, axis.normalized()).toRotationMatrix();
  T.translation() = t;
  return T;
}

// Four sweeps of one cylinder: 0 = [0, 40] deg, 1 = [30, 70], 2 = [60, 100] (each overlapping the next by
// 10 deg, a quarter of its width, and 0 and 2 not at all), 3 = [0, 40] deg but 500 mm along the axis,
// overlapping nothing. Each is stored in a frame of its own and placed by its exact pose.
class SweepGraph : public ::testing::Test {
 protected:
  SweepGraph() {
    poses_ = {Pose(0.0, Eigen::Vector3d::UnitZ(), Eigen::Vector3d::Zero()),
              Pose(25.0, Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(10.0, -20.0, 5.0)),
              Pose(-40.0, Eigen::Vector3d(0, 1, 1), Eigen::Vector3d(-30.0, 0.0, 12.0)),
              Pose(70.0, Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0.0, 300.0, 0.0))};
    clouds_ = {Sector(0.0, 40.0, 0.0, poses_[0]), Sector(30.0, 70.0, 0.0, poses_[1]),
               Sector(60.0, 100.0, 0.0, poses_[2]), Sector(0.0, 40.0, 500.0, poses_[3])};
    for (std::size_t k = 0; k < clouds_.size(); ++k)
      sweeps_.push_back(PrepareSweep(clouds_[k], SweepSurfaceOptions{}, "sector " + std::to_string(k)));
  }

  // Fraction of sweep k's normals that point away from the cylinder's axis (in the world).
  double OutwardFraction(std::size_t k) const {
    int outward = 0;
    const Eigen::Index n = clouds_[k].size();
    for (Eigen::Index r = 0; r < n; ++r) {
      const Eigen::Vector3d p = poses_[k] * clouds_[k].positions.row(r).transpose();
      const Eigen::Vector3d nw = poses_[k].linear() * sweeps_[k].normals.row(r).transpose();
      if (nw.dot(Eigen::Vector3d(p.x(), 0.0, p.z())) > 0.0) ++outward;
    }
    return double(outward) / double(n);
  }

  // Turns sweep k's normals outward (outward = true) or inward.
  void Face(std::size_t k, bool outward) {
    if ((OutwardFraction(k) > 0.5) != outward) sweeps_[k].FlipNormals();
  }

  // Faces sweep k outward where outward[k], inward elsewhere; orients the sweeps from sweep 0; every
  // normal of every sweep must then point outward.
  void ExpectOutwardAfterOrienting(const std::vector<bool>& outward) {
    for (std::size_t k = 0; k < outward.size(); ++k) Face(k, outward[k]);
    OrientSweeps(poses_, 2.0, 0, &sweeps_);
    for (std::size_t k = 0; k < sweeps_.size(); ++k) EXPECT_EQ(OutwardFraction(k), 1.0) << "sweep " << k;
  }

  std::vector<Rigid3> poses_;
  std::vector<PointCloud> clouds_;
  std::vector<SweepSurface> sweeps_;
};

TEST_F(SweepGraph, LinksExactlyTheOverlappingPairs) {
  for (std::size_t k = 0; k < sweeps_.size(); ++k) Face(k, true);
  const std::vector<SweepLink> links = FindSweepLinks(sweeps_, poses_, 2.0, 0.1);
  std::set<std::pair<std::size_t, std::size_t>> pairs;
  for (const SweepLink& l : links) {
    pairs.insert({l.i, l.j});
    EXPECT_LT(l.i, l.j);
    // A quarter of each sweep lies on its neighbour, and its edge row with it: a sample whose nearest
    // point is on the neighbour's border counts when it lies within one point spacing of it along the
    // surface (inside the neighbour's edge), so the fraction is a little over 0.25 (0.27-0.28 measured);
    // the next row out does not count.
    EXPECT_GT(l.overlap, 0.22) << l.i << "-" << l.j;
    EXPECT_LE(l.overlap, 0.30) << l.i << "-" << l.j;
  }
  const std::set<std::pair<std::size_t, std::size_t>> expected = {{0, 1}, {1, 2}};
  EXPECT_EQ(pairs, expected) << "0-2 do not overlap; sweep 3 overlaps nothing";

  // Sweep 3 is in no link: the caller sees it left out of the graph.
  for (const SweepLink& l : links) EXPECT_TRUE(l.i != 3 && l.j != 3);

  // A threshold above the overlap links nothing.
  EXPECT_TRUE(FindSweepLinks(sweeps_, poses_, 2.0, 0.5).empty());
}

TEST_F(SweepGraph, CorrespondencesOfEveryLinkBothWaysLieOnTheSurface) {
  for (std::size_t k = 0; k < sweeps_.size(); ++k) Face(k, true);
  const std::vector<SweepLink> links = FindSweepLinks(sweeps_, poses_, 2.0, 0.1);
  ASSERT_EQ(links.size(), 2u);
  const auto pairs = AllCorrespondences(sweeps_, poses_, links, 500, 2.0);
  std::set<std::pair<std::size_t, std::size_t>> directions;
  for (const SweepCorrespondence& c : pairs) directions.insert({c.i, c.j});
  const std::set<std::pair<std::size_t, std::size_t>> expected = {{0, 1}, {1, 0}, {1, 2}, {2, 1}};
  EXPECT_EQ(directions, expected);
  // At the exact poses both points lie on the same cylinder: the point-to-plane residual is the gap
  // between the chord and the tangent plane, d^2 / (2 * 50 mm) for points d apart; the nearest point is
  // at most half a grid diagonal (0.71 mm) away, 0.005 mm at worst (0.00075 mm RMS measured).
  EXPECT_LT(PointToPlaneRms(pairs, poses_), 0.003);
  // Moving sweep 1 by 0.5 mm along its neighbours' normals shows in the residual.
  std::vector<Rigid3> moved = poses_;
  moved[1] = Pose(0.0, Eigen::Vector3d::UnitZ(),
                  0.5 * Eigen::Vector3d(std::sin(35 * kDegree), 0.0, std::cos(35 * kDegree))) *
             poses_[1];
  // 0.5 mm times the cosine of 0 to 35 degrees between the shift and the normals (0.466 mm measured).
  EXPECT_GT(PointToPlaneRms(pairs, moved), 0.5 * std::cos(35 * kDegree));
  EXPECT_LT(PointToPlaneRms(pairs, moved), 0.5);
}

TEST_F(SweepGraph, OverlapRowsListEveryPointOfTheOverlapAndPairThemAll) {
  for (std::size_t k = 0; k < sweeps_.size(); ++k) Face(k, true);
  const std::vector<SweepLink> links = FindSweepLinks(sweeps_, poses_, 2.0, 0.1);
  ASSERT_EQ(links.size(), 2u);
  const auto rows = OverlapRows(sweeps_, poses_, links, 2.0);
  ASSERT_EQ(rows.size(), 4u);
  // Each list is exactly the source's points within 2 mm of a point of the target (brute force).
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const SweepLink& l = links[k / 2];
    const std::size_t target = k % 2 ? l.j : l.i, source = k % 2 ? l.i : l.j;
    std::vector<std::uint32_t> expected;
    for (Eigen::Index r = 0; r < clouds_[source].size(); ++r) {
      const Eigen::Vector3d x = poses_[source] * clouds_[source].positions.row(r).transpose();
      for (Eigen::Index q = 0; q < clouds_[target].size(); ++q) {
        if ((poses_[target] * clouds_[target].positions.row(q).transpose() - x).norm() <= 2.0) {
          expected.push_back(std::uint32_t(r));
          break;
        }
      }
    }
    EXPECT_EQ(rows[k], expected) << "list " << k;
  }
  // Paired from every point, each way, against the subsample (cube of 2 spacings: about a quarter of the
  // points): three to five times as many pairs, on the same surface.
  const auto every = AllCorrespondences(sweeps_, poses_, links, rows, 2.0);
  const auto subsample = AllCorrespondences(sweeps_, poses_, links, 100000, 2.0);
  EXPECT_GT(every.size(), 3 * subsample.size());
  EXPECT_LT(every.size(), 5 * subsample.size());
  EXPECT_LT(PointToPlaneRms(every, poses_), 0.003);
}

TEST_F(SweepGraph, OrientsEveryLinkedSweepToTheAnchorsSideThenOutward) {
  // Sweep 1 inward between two outward ones: it is turned to agree with them.
  ExpectOutwardAfterOrienting({true, false, true, true});
  // All inward but sweep 1: it follows the anchor inward, then the whole set is turned to face away from
  // its centroid, the isolated sweep 3 with it.
  ExpectOutwardAfterOrienting({false, true, false, false});
}

// PosesFromTree alone: a graph of four sweeps with given relative poses.
TEST(PosesFromTree, FollowsTheMaximumSpanningTreeOfTheSuccessfulLinks) {
  const Rigid3 T01 = Pose(10.0, Eigen::Vector3d::UnitX(), Eigen::Vector3d(1, 2, 3));
  const Rigid3 T02 = Pose(-20.0, Eigen::Vector3d::UnitY(), Eigen::Vector3d(-4, 0, 1));
  const Rigid3 wrong = Pose(90.0, Eigen::Vector3d::UnitZ(), Eigen::Vector3d(100, 0, 0));
  const Rigid3 anchor = Pose(30.0, Eigen::Vector3d(1, 1, 0), Eigen::Vector3d(5, 5, 5));
  // 0-1 and 0-2 overlap most; 1-2 overlaps less and its pose is wrong, so the tree must not use it;
  // 2-3 overlaps most of all but its registration failed, so sweep 3 is not placed.
  const std::vector<SweepLink> links = {{0, 1, 0.6}, {1, 2, 0.3}, {0, 2, 0.5}, {2, 3, 0.9}};
  const std::vector<Rigid3> T_i_j = {T01, wrong, T02, wrong};
  const std::vector<bool> ok = {true, true, true, false};
  const Rigid3 untouched = Pose(5.0, Eigen::Vector3d::UnitZ(), Eigen::Vector3d(7, 7, 7));
  std::vector<Rigid3> P = {anchor, Rigid3::Identity(), Rigid3::Identity(), untouched};
  PosesFromTree(links, T_i_j, ok, 0, &P);
  // Exact up to the rounding of two products of 4 x 4 matrices.
  EXPECT_TRUE(P[0].isApprox(anchor, 1e-12)) << "the anchor keeps its pose";
  EXPECT_TRUE(P[1].isApprox(anchor * T01, 1e-12));
  EXPECT_TRUE(P[2].isApprox(anchor * T02, 1e-12));
  EXPECT_TRUE(P[3].isApprox(untouched, 1e-12)) << "a sweep reached by no successful link keeps its pose";

  // Grown from sweep 2, sweep 0 is placed by the inverse of its link.
  std::vector<Rigid3> Q = {Rigid3::Identity(), Rigid3::Identity(), anchor, untouched};
  PosesFromTree(links, T_i_j, ok, 2, &Q);
  EXPECT_TRUE(Q[0].isApprox(anchor * T02.inverse(), 1e-12));
  EXPECT_TRUE(Q[1].isApprox(anchor * T02.inverse() * T01, 1e-12));
}

}  // namespace
}  // namespace pectus
