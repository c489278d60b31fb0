// pectus datasets (internal): the rigid error a tracker adds to one sweep's pose (docs/datasets.md, "The
// tracker's error").
#pragma once

#include <Eigen/Core>
#include <random>

#include "datasets/scan_simulator.h"
#include "shape/core/geometry.h"

namespace pectus::datasets::internal {

/// One sweep's tracker error: x_reported = error * x_true.
struct TrackerError {
  Rigid3 error = Rigid3::Identity();
  double angle_deg = 0.0;    ///< rotation angle about an axis through the pivot
  double shift_mm = 0.0;     ///< length of the translation beyond the rotation about the pivot
  double skin_rms_mm = 0.0;  ///< RMS displacement of the true points, mm
};

/// Draws the error of one sweep: a rotation about a random axis through `pivot` and a shift in a random
/// direction (in that order from `rng`, then, for TrackerDraw::kUniform, the magnitudes), of
/// options.tracker_deg and options.tracker_mm, or scaled together so that the RMS displacement of
/// `true_points` (#points by 3, mm) is options.tracker_skin_mm when that is > 0.
TrackerError DrawTrackerError(const ScanOptions& options, const Eigen::Vector3d& pivot,
                              const Points3& true_points, std::mt19937_64* rng);

/// RMS displacement of the points (#points by 3) by `T`, mm; 0 for no points.
double RmsDisplacement(const Rigid3& T, const Points3& points);

}  // namespace pectus::datasets::internal
