// pectus: the point levels of the RBF implicit (shape/rbf_implicit.h): input points averaged per cube at
// a spacing, with counts, k-d tree and off-surface distances.
#pragma once

#include <memory>

#include "registration/kdtree.h"
#include "shape/core/geometry.h"

namespace pectus {

/// Points averaged per cube (and per side of a thin sheet: points whose normals oppose the first point of
/// their cube are averaged apart), with their counts. Deterministic.
struct RbfLevel {
  double spacing = 0.0;                 ///< cube side (mm)
  Points3 positions;                    ///< averaged points (mm)
  Points3 normals;                      ///< their unit normals
  Eigen::VectorXd counts;               ///< input points averaged into each
  Eigen::VectorXd eps_plus, eps_minus;  ///< off-surface distances per point (mm; 0 = none), centre levels
  std::unique_ptr<KdTree3> tree;        ///< over positions
};

/// Averages weighted points per cube of side `spacing` into `level` (its tree included).
/// @param[in] positions, normals  #points by 3 (mm, unit)
/// @param[in] counts              weight of each point (the input points it stands for)
void AverageByVoxel(const Points3& positions, const Points3& normals, const Eigen::VectorXd& counts,
                    double spacing, RbfLevel* level);

/// Off-surface distances of a centre level (Carr et al. 2001, Sec. 3.1: an off-surface point must not lie
/// nearer to other data than to its own point): eps, halved up to three times until the point y +- eps n
/// is at least 0.7 eps from every point of `fine`, else 0 (no constraint on that side).
void SetOffSurfaceDistances(const RbfLevel& fine, double eps_mm, RbfLevel* level);

}  // namespace pectus
