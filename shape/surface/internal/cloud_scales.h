// pectus: the scales of a point cloud that set the defaults of a reconstruction: how densely it samples
// its surface (point spacing) and how noisy it is (noise level), both measured in O(N).
#pragma once

#include "shape/core/geometry.h"

namespace pectus {

/// Side of the square each point covers (mm): from the radius r of the 16 nearest neighbours,
/// pi r^2 = 16 s^2, median over 512 evenly picked points; a dense cloud is measured on a random subset.
/// Unlike the nearest-neighbour distance it does not shrink where overlapping sweeps interleave.
/// @param[in] points  #points by 3 (mm), at least 17
double PointSpacing(const Points3& points);

/// Noise level of the points about their surface (mm): the points are binned in cubes of side
/// 4.5 point spacings (about 20 points each, whatever the density), and the noise is the median, over up
/// to 512 cubes with at least 10 points, of the RMS distance of a cube's points to their best plane
/// (sqrt of the covariance's smallest eigenvalue). Includes the disagreement of overlapping sweeps.
/// @param[in] points   #points by 3 (mm)
/// @param[in] spacing  PointSpacing(points) (mm)
double NoiseLevel(const Points3& points, double spacing);

}  // namespace pectus
