// Tests of datasets/internal/tracker_error through SimulateScan: the tracker's error about the sensor's
// pivot, drawn exactly or uniformly, or scaled to a displacement at the skin, measured independently on
// each sweep's true points and its true pose.
#include "datasets/internal/tracker_error.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "datasets/chest_population.h"
#include "datasets/surface_query.h"
#include "tests/datasets/sample_chest.h"

namespace pectus::datasets::internal {
namespace {

ScanOptions Lever() {
  ScanOptions o;
  o.sweeps = 6;
  o.spacing_mm = 3.0;
  o.tracker_pivot = TrackerPivot::kLever;
  o.tracker_lever_mm = 200.0;
  return o;
}

// RMS of |x_reported - x_true| over the true points, from T_scan_sweep alone.
double MeasuredSkinRms(const SweepTruth& t) {
  const Rigid3 error = t.T_scan_sweep.inverse();
  double sum = 0.0;
  for (Eigen::Index i = 0; i < t.true_points.rows(); ++i) {
    const Eigen::Vector3d p = t.true_points.row(i).transpose();
    sum += (error * p - p).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(t.true_points.rows()));
}

// The pivot of kLever is the sensor: tracker_lever_mm out from the sweep's skin along its line of sight
// (it lies 150-200 mm outside the skin, the skin curving away under it), and an exact draw turns the
// sweep by exactly tracker_deg.
TEST(TrackerError, LeverPivotLiesOutsideTheSkinAtTheLever) {
  const ChestSurface surface = SampleChest();
  ScanOptions o = Lever();
  o.tracker_deg = 0.8;
  o.tracker_mm = 0.0;
  const Scan scan = SimulateScan(surface, o, 4);
  for (const Sweep& s : scan.sweeps) {
    EXPECT_GT(SignedDistance(surface, s.truth.pivot), 150.0);
    EXPECT_LT(SignedDistance(surface, s.truth.pivot), 200.0 + 1e-6);
    EXPECT_NEAR(Eigen::AngleAxisd(s.truth.T_scan_sweep.linear()).angle() * 180.0 / std::numbers::pi, 0.8,
                1e-9);
    EXPECT_NEAR(s.truth.skin_rms_mm, MeasuredSkinRms(s.truth), 1e-9);
  }
}

// 0.8 degrees about a pivot ~200 mm off the skin: a rotation about a random axis moves a point at r from
// the pivot by theta |r| sin(angle to the axis), whose mean square over axes is (2/3) theta^2 |r|^2. Over
// 24 sweeps the mean of rms^2 / ((2/3) theta^2 mean |r|^2) is 1 within 0.3 (the ratio of one sweep lies
// in [0, 1.5] with sd 0.45; 0.3 is 3.3 sd of the mean), and the RMS at the skin is about 2.8 mm.
TEST(TrackerError, RotationAboutTheLeverDisplacesTheSkinByTheLeverTimesTheAngle) {
  const ChestSurface surface = SampleChest();
  ScanOptions o = Lever();
  o.tracker_deg = 0.8;
  o.tracker_mm = 0.0;
  const double theta = 0.8 * std::numbers::pi / 180.0;
  double ratio = 0.0, skin = 0.0;
  int count = 0;
  for (std::uint64_t seed : {1, 2, 3, 4}) {
    for (const Sweep& s : SimulateScan(surface, o, seed).sweeps) {
      const Points3& p = s.truth.true_points;
      const double r2 = (p.rowwise() - s.truth.pivot.transpose()).rowwise().squaredNorm().mean();
      ratio += s.truth.skin_rms_mm * s.truth.skin_rms_mm / (2.0 / 3.0 * theta * theta * r2);
      skin += s.truth.skin_rms_mm * s.truth.skin_rms_mm;
      ++count;
    }
  }
  EXPECT_NEAR(ratio / count, 1.0, 0.3);
  EXPECT_NEAR(std::sqrt(skin / count), 200.0 * theta * std::sqrt(2.0 / 3.0), 0.6);  // 2.28 mm
}

// tracker_skin_mm: every sweep's true points move by exactly that RMS (1e-6 mm), measured from the true
// pose alone, for either pivot, with rotation and translation in the ratio tracker_deg : tracker_mm.
TEST(TrackerError, SkinDisplacementIsTheRequestedRms) {
  const ChestSurface surface = SampleChest();
  for (TrackerPivot pivot : {TrackerPivot::kWand, TrackerPivot::kLever}) {
    for (double skin : {0.5, 2.0, 6.0}) {
      ScanOptions o = Lever();
      o.tracker_pivot = pivot;
      o.tracker_skin_mm = skin;
      for (const Sweep& s : SimulateScan(surface, o, 9).sweeps) {
        EXPECT_NEAR(MeasuredSkinRms(s.truth), skin, 1e-6);
        EXPECT_NEAR(s.truth.skin_rms_mm, skin, 1e-6);
        EXPECT_NEAR(s.truth.rotation_error_deg / s.truth.translation_error_mm, 0.5 / 1.5, 1e-9);
      }
    }
  }
}

// A uniform draw: magnitudes within [0, the given value], spread over it (24 sweeps: the smallest below
// 0.35 and the largest above 0.65 of it, each failing with probability 0.65^24 = 3e-5).
TEST(TrackerError, UniformDrawSpreadsTheMagnitudesUpToTheGivenValues) {
  const ChestSurface surface = SampleChest();
  ScanOptions o = Lever();
  o.tracker_draw = TrackerDraw::kUniform;
  o.tracker_deg = 2.0;
  o.tracker_mm = 3.0;
  std::vector<double> angles, shifts, skins;
  for (std::uint64_t seed : {1, 2, 3, 4}) {
    for (const Sweep& s : SimulateScan(surface, o, seed).sweeps) {
      angles.push_back(s.truth.rotation_error_deg / 2.0);
      shifts.push_back(s.truth.translation_error_mm / 3.0);
    }
    o.tracker_skin_mm = 4.0;
    for (const Sweep& s : SimulateScan(surface, o, seed).sweeps) skins.push_back(s.truth.skin_rms_mm / 4.0);
    o.tracker_skin_mm = 0.0;
  }
  for (const std::vector<double>* v : {&angles, &shifts, &skins}) {
    EXPECT_GE(*std::min_element(v->begin(), v->end()), 0.0);
    EXPECT_LE(*std::max_element(v->begin(), v->end()), 1.0 + 1e-9);
    EXPECT_LT(*std::min_element(v->begin(), v->end()), 0.35);
    EXPECT_GT(*std::max_element(v->begin(), v->end()), 0.65);
  }
}

TEST(TrackerError, ASkinDisplacementNeedsAnErrorShape) {
  ScanOptions o;
  o.tracker_skin_mm = 2.0;
  o.tracker_deg = o.tracker_mm = 0.0;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("ratio"), std::string::npos);
  o.tracker_mm = 1.0;
  EXPECT_TRUE(o.IsValid(&why));
}

}  // namespace
}  // namespace pectus::datasets::internal
