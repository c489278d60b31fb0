#include "planner_plugin/trainer/trainer_scene.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <utility>

#include "tests/planner_plugin/trainer/trainer_test_scene.h"
#include "tests/support/require_shared_data.h"

namespace pectus::trainer {
namespace {

using testing::SceneOf;

// Every edge shared by exactly two faces, in opposite directions; and the enclosed volume positive.
void ExpectClosedAndOutward(const Points3& v, const Faces3& f, const char* what) {
  std::map<std::pair<int, int>, int> directed;
  double volume = 0;
  for (Eigen::Index i = 0; i < f.rows(); ++i) {
    for (int k = 0; k < 3; ++k) ++directed[{f(i, k), f(i, (k + 1) % 3)}];
    volume += Eigen::Vector3d(v.row(f(i, 0)))
                  .dot(Eigen::Vector3d(v.row(f(i, 1))).cross(Eigen::Vector3d(v.row(f(i, 2))))) /
              6;
  }
  int bad = 0;
  for (const auto& [edge, n] : directed) {
    if (n != 1 || directed.count({edge.second, edge.first}) != 1) ++bad;
  }
  EXPECT_EQ(bad, 0) << what << ": edges not shared by exactly two opposite faces";
  EXPECT_GT(volume, 0) << what;
}

// How many edges of (v, f) cross the surface in `grid` (in either direction).
int EdgesCrossing(const Points3& v, const Faces3& f, const TriangleGrid& grid) {
  int n = 0;
  SurfaceHit hit;
  for (Eigen::Index i = 0; i < f.rows(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d a = v.row(f(i, k)), b = v.row(f(i, (k + 1) % 3));
      if (grid.FirstHit(a, b, nullptr, 0, &hit) || grid.FirstHit(b, a, nullptr, 0, &hit)) ++n;
    }
  }
  return n;
}

// The smallest distance from the vertices of `v` to the surface in `grid`, up to `reach`.
double MinDistance(const Points3& v, const TriangleGrid& grid, double reach) {
  double best = reach;
  SurfaceHit hit;
  for (Eigen::Index i = 0; i < v.rows(); ++i) {
    if (grid.Nearest(v.row(i).transpose(), best, &hit)) best = hit.distance_mm;
  }
  return best;
}

TEST(TrainerScene, OrgansAreClosedAndPlacedByTheirRules) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable);
  const TrainerSceneOptions options;
  // Patients 57 (depression 21 mm) and 3 (40 mm); 48 (none) passes too (slower under the sanitizers).
  std::map<double, double> shift_by_depression;
  for (int patient : {57, 3}) {
    const TrainerScene& s = SceneOf(patient);
    const planner::RibcageMeasurements& m = testing::RibcageOf(patient).measured;
    SCOPED_TRACE("patient " + std::to_string(patient));
    for (const OrganPlacement* o : {&s.pericardium, &s.right_lung, &s.left_lung}) {
      ExpectClosedAndOutward(o->mesh.vertices.positions, o->mesh.faces, "organ");
      // Nothing crosses a bone: no organ edge through a bone face, no bone edge through the organ.
      const TriangleGrid g(o->mesh.vertices.positions, o->mesh.faces, 6.0);
      EXPECT_EQ(EdgesCrossing(o->mesh.vertices.positions, o->mesh.faces, s.bone_grid), 0);
      EXPECT_EQ(EdgesCrossing(s.bone_vertices, s.bone_faces, g), 0);
    }
    // The pericardium's nearest bone is the mediastinal gap away (measured on the meshes, both ways).
    const double gap = std::min(MinDistance(s.pericardium.mesh.vertices.positions, s.bone_grid, 50),
                                MinDistance(s.bone_vertices, s.pericardium_grid, 50));
    EXPECT_NEAR(gap, options.mediastinal_gap_mm, 0.05);
    // Against the sternum: its nearest approach to the sternum alone is the gap, within 25 mm.
    Faces3 sternum(s.bone_faces.rows(), 3);
    Eigen::Index n = 0;
    for (Eigen::Index f = 0; f < s.bone_faces.rows(); ++f) {
      if (s.bone_parts(f) == 0) sternum.row(n++) = s.bone_faces.row(f);
    }
    sternum.conservativeResize(n, 3);
    const TriangleGrid sternum_grid(s.bone_vertices, sternum, 6.0);
    const double sternum_gap = MinDistance(s.pericardium.mesh.vertices.positions, sternum_grid, 100);
    EXPECT_GE(sternum_gap, options.mediastinal_gap_mm - 0.05);
    EXPECT_LT(sternum_gap, options.mediastinal_gap_mm + 25);
    // The pericardium's centre (mean of its vertices) lies left by the rule's shift.
    const double centre_x = s.pericardium.mesh.vertices.positions.col(0).mean();
    EXPECT_NEAR(centre_x, options.heart_shift_mm + options.heart_shift_per_depression * m.depression_mm,
                1e-6);
    shift_by_depression[m.depression_mm] = centre_x;
    // The lungs keep the pleural gap from the bones and stay off the pericardium.
    for (const OrganPlacement* lung : {&s.right_lung, &s.left_lung}) {
      EXPECT_GE(MinDistance(lung->mesh.vertices.positions, s.bone_grid, 50), options.pleural_gap_mm - 0.05);
      EXPECT_GE(MinDistance(lung->mesh.vertices.positions, s.pericardium_grid, 50), 2.0 - 0.05);
    }
    EXPECT_LT(s.right_lung.centre.x(), 0);
    EXPECT_GT(s.left_lung.centre.x(), 0);
    std::printf(
        "patient %d: depression %.1f mm, pericardium at x %.1f, %.2f mm from bone, %.1f mm behind the "
        "sternum; lungs %.0f / %.0f mm wide\n",
        patient, m.depression_mm, centre_x, gap, sternum_gap, 2 * s.right_lung.semi_axes.x(),
        2 * s.left_lung.semi_axes.x());
  }
  // The leftward shift grows with the depression.
  double last = -1e9;
  for (const auto& [depression, x] : shift_by_depression) {
    EXPECT_GT(x, last) << "at depression " << depression;
    last = x;
  }
}

TEST(TrainerScene, TunnelEntersTheRightSpaceCrossesAboveThePericardiumAndLeavesTheMatchingLeftSpace) {
  PECTUS_REQUIRE_SHARED_FILE(testing_support::kPatientTable);
  for (int patient : {57}) {  // 3 and 48 too when measured (docs/trainer.md); one keeps the run short
    const TrainerScene& s = SceneOf(patient);
    SCOPED_TRACE("patient " + std::to_string(patient));
    const PlannedTunnel& t = s.tunnel;
    EXPECT_EQ(t.entry.side, -1);
    EXPECT_EQ(t.exit.side, 1);
    EXPECT_GE(t.entry.number, 2);
    EXPECT_EQ(t.entry.number, t.exit.number);
    // The ports lie in the spaces the plan names.
    EXPECT_EQ(s.SpaceAt(t.entry_port), t.entry);
    EXPECT_EQ(s.SpaceAt(t.exit_port), t.exit);
    // One space up (half-way to the rib above's own port height) is another space.
    const IntercostalSpace above = s.SpaceAt(t.entry_port + Eigen::Vector3d(0, 0, 22));
    EXPECT_TRUE(above == IntercostalSpace{} || above.number == t.entry.number - 1) << above.Name();
    // Under the sternum: the midline point lies between the sternum's back and the pericardium.
    Eigen::Index mid = 0;
    t.points.col(0).cwiseAbs().minCoeff(&mid);
    EXPECT_GT(t.points(mid, 1), s.sternum_back_y_mm);
    // Never on the pericardium: the whole tunnel keeps about half the gap from it (4.5 mm of 5).
    double nearest = 1e9;
    for (Eigen::Index i = 0; i < t.points.rows(); ++i) {
      nearest = std::min(nearest, s.DistanceToPericardium(t.points.row(i).transpose()));
    }
    EXPECT_GE(nearest, 4.5);
    std::printf("patient %d: tunnel %.0f mm, %s -> %s, %.1f mm from the pericardium at its nearest\n",
                patient, t.length_mm, t.entry.Name().c_str(), t.exit.Name().c_str(), nearest);
  }
}

}  // namespace
}  // namespace pectus::trainer
