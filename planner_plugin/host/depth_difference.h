// pectus planner host: how far a surface lies in front of (or behind) points, along one direction: the
// depth difference between two chests as a surgeon reads it (the anterior direction), fast enough to
// score hundreds of candidate plans (a 2D bin grid over the surface seen along the direction).
#pragma once

#include <Eigen/Core>

#include "shape/core/geometry.h"

namespace pectus::planner {

/// For each point p (#points by 3, mm), the t (mm) with p + t * direction on `surface`: positive when
/// the surface lies ahead of the point along `direction` (unit). Where the line meets the surface more
/// than once (a fold), the smallest |t|; NaN where it misses the surface (the point lies beyond it).
/// O(#points + #faces) for a surface that is a height field along `direction`.
Eigen::VectorXd DepthDifference(const Points3& points, const Eigen::Vector3d& direction,
                                const TriangleMesh& surface);

}  // namespace pectus::planner
