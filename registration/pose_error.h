// pectus: how far apart two estimates of one transform are, for tests, benchmarks and reports.
#pragma once

#include <vector>

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

/// The rigid motion G that best maps one placement of several point sets onto another: it minimises
/// sum |G from[s] x - to[s] x|^2 over every `stride`-th point x of every set s (Umeyama, no scale). Two
/// alignments of the same sweeps (a merge's poses and the true ones, or a published .conf) may differ by
/// such a common motion, which no overlap can observe: remove it before comparing the sweeps one by one.
/// @param[in] sets    the point sets, each in its own frame (mm)
/// @param[in] from    one pose per set: the placement to move
/// @param[in] to      one pose per set: the placement to reach
/// @param[in] stride  every stride-th point of a set counts (>= 1)
/// Throws Error(kUsage) for sizes that disagree or a stride < 1, Error(kBadInput) for fewer than 3 points.
Rigid3 BestCommonMotion(const std::vector<PointCloud>& sets, const std::vector<Rigid3>& from,
                        const std::vector<Rigid3>& to, Eigen::Index stride = 1);

}  // namespace pectus
