#include "shape/surface/sweep_surface.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "shape/core/error.h"

namespace pectus {
namespace {

// A 60 x 40 mm grid patch of the plane z = 0 with 0.5 mm spacing and a hole of radius 5 mm at (20, 20).
PointCloud Patch() {
  std::vector<Eigen::Vector3d> p;
  for (double x = 0; x <= 60.0 + 1e-9; x += 0.5)
    for (double y = 0; y <= 40.0 + 1e-9; y += 0.5)
      if (std::hypot(x - 20.0, y - 20.0) >= 5.0) p.emplace_back(x, y, 0.0);
  PointCloud c;
  c.positions.resize(Eigen::Index(p.size()), 3);
  for (std::size_t i = 0; i < p.size(); ++i) c.positions.row(Eigen::Index(i)) = p[i].transpose();
  return c;
}

TEST(SweepSurface, FindsTheBorderAndTheRimOfHoles) {
  const PointCloud patch = Patch();
  const SweepSurface s = PrepareSweep(patch, SweepSurfaceOptions{}, "patch");
  EXPECT_NEAR(s.spacing_mm, 0.5, 1e-9);
  int interior_flagged = 0, edge_missed = 0;
  for (Eigen::Index i = 0; i < patch.size(); ++i) {
    const double x = patch.positions(i, 0), y = patch.positions(i, 1);
    const double to_edge = std::min({x, 60.0 - x, y, 40.0 - y, std::hypot(x - 20.0, y - 20.0) - 5.0});
    if (to_edge < 1e-9 && !s.border[std::size_t(i)]) ++edge_missed;
    if (to_edge > 1.6 && s.border[std::size_t(i)]) ++interior_flagged;
    EXPECT_NEAR(std::abs(s.normals(i, 2)), 1.0, 1e-9);
  }
  EXPECT_EQ(edge_missed, 0) << "every point on the edge or the rim is a border point";
  EXPECT_EQ(interior_flagged, 0) << "no point 1.6 mm inside is";
  EXPECT_FALSE(s.samples.empty());
}

TEST(SweepSurface, CorrespondencesMeasureTheOffsetAndSkipTheEdge) {
  const PointCloud a = Patch();
  PointCloud b = a;
  b.positions.col(0).array() += 30.0;  // half overlapping along x
  std::vector<SweepSurface> s;
  s.push_back(PrepareSweep(a, SweepSurfaceOptions{}, "a"));
  s.push_back(PrepareSweep(b, SweepSurfaceOptions{}, "b"));
  if (s[0].normals(0, 2) * s[1].normals(0, 2) < 0) s[1].FlipNormals();
  Rigid3 lift = Rigid3::Identity();
  lift.translation() = Eigen::Vector3d(0.0, 0.0, 0.2);  // sweep b 0.2 mm above a
  const std::vector<Rigid3> poses = {Rigid3::Identity(), lift};
  const auto pairs = FindSweepCorrespondences(s, poses, 0, 1, 100000, 2.0);
  ASSERT_GT(pairs.size(), 100u);
  for (const auto& c : pairs) {
    EXPECT_GE(c.p.x(), 30.0 - 1e-9);
    EXPECT_LE(c.p.x(), 60.0 + 1e-9) << "b's points beyond a's edge are not paired with it";
    EXPECT_LT(c.q.x(), 60.0) << "a's border points are never targets";
  }
  EXPECT_NEAR(PointToPlaneRms(pairs, poses), 0.2, 1e-9);
  // Normals of opposite sides never pair (the two sides of a thin part).
  s[1].FlipNormals();
  EXPECT_TRUE(FindSweepCorrespondences(s, poses, 0, 1, 100000, 2.0).empty());
}

// A 40 mm strip wrapped 110 degrees either way around a cylinder of radius 120 mm (axis y), 1 mm grid:
// a handheld sweep carried around a chest, the wand facing the skin all along.
PointCloud WrappedStrip() {
  std::vector<Eigen::Vector3d> p;
  const double radius = 120.0, half_arc = 110.0 * M_PI / 180.0;
  for (double s = -half_arc * radius; s <= half_arc * radius + 1e-9; s += 1.0)
    for (double y = 0.0; y <= 40.0 + 1e-9; y += 1.0)
      p.emplace_back(radius * std::sin(s / radius), y, radius * std::cos(s / radius));
  PointCloud c;
  c.positions.resize(Eigen::Index(p.size()), 3);
  for (std::size_t i = 0; i < p.size(); ++i) c.positions.row(Eigen::Index(i)) = p[i].transpose();
  return c;
}

// Seen from where the wand was (the mean normal over a stretch of the strip as long as half its width),
// no point of the strip is grazing and every normal faces out, round to 110 degrees from the sweep's mean
// normal; from the sweep's mean normal alone (sight_radius_widths 0), every point beyond 65 degrees is
// grazing and those beyond 90 face in.
TEST(SweepSurface, AWrappedStripIsSeenHeadOnAlongItsLength) {
  const PointCloud strip = WrappedStrip();
  const SweepSurface local = PrepareSweep(strip, SweepSurfaceOptions{}, "strip");
  SweepSurfaceOptions one_view;
  one_view.sight_radius_widths = 0.0;
  const SweepSurface global = PrepareSweep(strip, one_view, "strip");
  int local_grazing = 0, local_inward = 0, global_wrong_grazing = 0, global_inward_beyond_90 = 0,
      beyond_90 = 0;
  for (Eigen::Index i = 0; i < strip.size(); ++i) {
    const Eigen::Vector3d x = strip.positions.row(i).transpose();
    const Eigen::Vector3d out = Eigen::Vector3d(x.x(), 0.0, x.z()).normalized();
    const double angle = std::acos(std::clamp(out.z(), -1.0, 1.0)) * 180.0 / M_PI;  // from the mean normal
    local_grazing += local.grazing[std::size_t(i)];
    local_inward += local.normals.row(i).dot(out.transpose()) < 0.9;
    if (angle > 66.0 && !global.grazing[std::size_t(i)]) ++global_wrong_grazing;
    if (angle < 64.0 && global.grazing[std::size_t(i)]) ++global_wrong_grazing;
    if (angle > 91.0) {
      ++beyond_90;
      global_inward_beyond_90 += global.normals.row(i).dot(out.transpose()) < -0.9;
    }
  }
  EXPECT_TRUE(local.scanner_moved);  // evenly sampled: a wand carried along it
  EXPECT_EQ(local_grazing, 0);
  EXPECT_EQ(local_inward, 0);
  EXPECT_EQ(global_wrong_grazing, 0);
  EXPECT_GT(beyond_90, 1000);
  EXPECT_EQ(global_inward_beyond_90, beyond_90);
}

// A scanner standing still on the z axis: a 0.5 mm grid in its image plane cast on a cap of a sphere of
// radius 60 mm, out to 80 degrees, so that the surface is sampled at cos(theta) of the density facing it.
// One line of sight, the sweep's mean normal: every point beyond 65 degrees is grazing, none within.
TEST(SweepSurface, AScanFromAScannerStandingStillKeepsOneLineOfSight) {
  std::vector<Eigen::Vector3d> p;
  const double radius = 60.0, rim = radius * std::sin(80.0 * M_PI / 180.0);
  for (double x = -rim; x <= rim; x += 0.5)
    for (double y = -rim; y <= rim; y += 0.5)
      if (x * x + y * y <= rim * rim) p.emplace_back(x, y, std::sqrt(radius * radius - x * x - y * y));
  PointCloud cap;
  cap.positions.resize(Eigen::Index(p.size()), 3);
  for (std::size_t i = 0; i < p.size(); ++i) cap.positions.row(Eigen::Index(i)) = p[i].transpose();
  const SweepSurface s = PrepareSweep(cap, SweepSurfaceOptions{}, "cap");
  EXPECT_FALSE(s.scanner_moved);
  int wrong = 0, beyond = 0;
  for (Eigen::Index i = 0; i < cap.size(); ++i) {
    const double angle = std::acos(std::clamp(cap.positions(i, 2) / radius, -1.0, 1.0)) * 180.0 / M_PI;
    if (angle > 66.0) ++beyond;
    if ((angle > 66.0 && !s.grazing[std::size_t(i)]) || (angle < 64.0 && s.grazing[std::size_t(i)])) ++wrong;
  }
  EXPECT_GT(beyond, 1000);
  EXPECT_EQ(wrong, 0);
}

TEST(SweepSurface, TooFewPointsIsBadInput) {
  PointCloud c;
  c.positions = Points3::Random(5, 3);
  EXPECT_THROW(PrepareSweep(c, SweepSurfaceOptions{}, "tiny"), Error);
}

}  // namespace
}  // namespace pectus
