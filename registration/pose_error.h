// pectus: how far apart two estimates of one transform are, for tests, benchmarks and reports.
#pragma once

#include "shape/core/geometry.h"

namespace pectus {

/// The difference between an estimated and a true transform T_target_source.
struct PoseError {
  double rotation_deg = 0.0;    ///< angle of R_estimate R_truth^T (degrees)
  double translation_mm = 0.0;  ///< |T_estimate c - T_truth c| at the point c given (mm)
  double scale_ratio = 1.0;     ///< s_estimate / s_truth
};

/// Compares two transforms. The translation error is measured at a point of the source (its centroid,
/// say), so that it does not depend on where the source frame's origin happens to be: for data 10 km
/// from the origin a tiny rotation error would otherwise read as kilometres of translation.
/// @param[in] estimate  estimated T_target_source
/// @param[in] truth     true T_target_source
/// @param[in] at        a point in the source frame (mm)
PoseError ComparePoses(const Similarity3& estimate, const Similarity3& truth, const Eigen::Vector3d& at);

/// RMS over the rows of `points` (source frame, mm) of |a x - b x| (mm): how far the placements of a
/// scan by two transforms are apart.
double RmsDisplacement(const Points3& points, const Similarity3& a, const Similarity3& b);

}  // namespace pectus
