#include "planner_plugin/host/plan_scoring.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "analytic_chest.h"
#include "planner_plugin/host/average_chest.h"

namespace pectus::planner {
namespace {

AverageChest Average() {
  AverageChest average;
  average.mesh = testing::AnalyticChestGrid();
  DetectGrid(average.mesh, &average.grid_columns, &average.grid_rows);
  average.landmarks = GridLandmarks(average.mesh, average.grid_columns, average.grid_rows);
  average.landmark_source = "analytic";
  return average;
}

// The predicted chest: a larger, finer grid of the same surface (so it covers the average chest), in
// another frame, with an optional bump of `bump_mm` along the normal centred mid-chest.
struct Predicted {
  TriangleMesh mesh;
  LandmarkSet landmarks;
};
Predicted MakePredicted(const Similarity3& T_patient_average, double bump_mm) {
  Predicted p;
  p.mesh = testing::AnalyticChestGrid(61, 81, 150, 110, 120, 230);
  Points3& x = p.mesh.vertices.positions;
  const double shift = 30;  // the finer grid starts 30 mm above the notch
  for (Eigen::Index i = 0; i < x.rows(); ++i) x(i, 1) += shift;
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const double r2 = (x(i, 0) * x(i, 0) + (x(i, 1) + 85) * (x(i, 1) + 85)) / (25.0 * 25.0);
    const double nx = x(i, 0) / (150.0 * 150.0), nz = x(i, 2) / (110.0 * 110.0);  // outward normal (x, z)
    const double norm = std::hypot(nx, nz);
    x(i, 0) += bump_mm * std::exp(-r2) * nx / norm;
    x(i, 2) += bump_mm * std::exp(-r2) * nz / norm;
  }
  const AverageChest a = Average();
  p.landmarks = a.landmarks;
  x = T_patient_average.Apply(x);
  p.landmarks = p.landmarks.Transformed(T_patient_average);
  return p;
}

Similarity3 PatientFrame() {
  Similarity3 T;
  T.scale = 0.85;  // the patient is smaller than the average chest
  // pectus scan frame (x across, y up, z anterior) to LPS (x left, y posterior, z up), and elsewhere.
  T.rotation << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  T.translation = Eigen::Vector3d(10, -20, 300);
  return T;
}

TEST(PlanScoring, TheSameChestInAnotherFrameScoresZero) {
  const AverageChest average = Average();
  const Predicted p = MakePredicted(PatientFrame(), 0.0);
  const PlanScore s = ScorePlan(p.mesh, p.landmarks, average);
  EXPECT_NEAR(s.registration.T_target_source.scale, 1.0 / 0.85, 1e-9);
  EXPECT_LT(s.registration.landmark_rms_mm, 1e-9);
  EXPECT_EQ(s.uncovered, 0);
  EXPECT_EQ(s.roi.count, average.mesh.num_vertices());
  // Interpolation between the finer grid's vertices only: the surfaces coincide to well under 0.1 mm.
  EXPECT_LT(s.roi.max_abs, 0.1);
  EXPECT_GT(s.central_roi.count, 0);
  EXPECT_LT(s.central_roi.count, s.roi.count);
}

TEST(PlanScoring, ABumpOfKnownHeightShowsAsThatDifferenceWhereItIs) {
  const AverageChest average = Average();
  const Predicted p = MakePredicted(PatientFrame(), 6.0);
  const PlanScore s = ScorePlan(p.mesh, p.landmarks, average);
  // The bump (in the average chest's size: 6 mm) stands in front of the average chest: positive.
  EXPECT_NEAR(s.roi.max, 6.0, 0.15);
  EXPECT_GT(s.roi.min, -0.1);
  // It is in the middle of the chest, so the central region holds the maximum.
  EXPECT_NEAR(s.central_roi.max_abs, s.roi.max_abs, 1e-12);
  // The predicted skin's own map agrees where it overlaps the average chest, and is NaN beyond it.
  Eigen::Index inside = 0, outside = 0;
  double largest = 0;
  for (Eigen::Index i = 0; i < s.predicted_distance_mm.size(); ++i) {
    if (std::isnan(s.predicted_distance_mm(i))) {
      ++outside;
    } else {
      ++inside;
      largest = std::max(largest, s.predicted_distance_mm(i));
    }
  }
  EXPECT_GT(outside, 0);
  EXPECT_GT(inside, 0);
  EXPECT_NEAR(largest, 6.0, 0.15);
}

TEST(PlanScoring, AverageChestTheSkinDoesNotReachIsCountedNotScored) {
  const AverageChest average = Average();
  // A predicted chest that covers only the upper half of the average chest.
  Predicted p = MakePredicted(Similarity3{}, 0.0);
  TriangleMesh upper;
  upper.vertices = p.mesh.vertices;
  std::vector<Eigen::Index> keep;
  for (Eigen::Index f = 0; f < p.mesh.num_faces(); ++f) {
    bool high = true;
    for (int c = 0; c < 3; ++c) high = high && p.mesh.vertices.positions(p.mesh.faces(f, c), 1) > -80;
    if (high) keep.push_back(f);
  }
  upper.faces.resize(static_cast<Eigen::Index>(keep.size()), 3);
  for (std::size_t k = 0; k < keep.size(); ++k)
    upper.faces.row(static_cast<Eigen::Index>(k)) = p.mesh.faces.row(keep[k]);
  const PlanScore s = ScorePlan(upper, p.landmarks, average);
  EXPECT_GT(s.uncovered, average.mesh.num_vertices() / 3);
  EXPECT_EQ(s.roi.count + s.uncovered, average.mesh.num_vertices());
  EXPECT_LT(s.roi.max_abs, 0.1);
}

}  // namespace
}  // namespace pectus::planner
