// pectus: clean-up of a merged cloud: blending of overlapping sweeps along the normals, statistical
// outlier removal, and picking rows of a cloud.
#pragma once

#include <cstdint>
#include <vector>

#include "shape/core/geometry.h"

namespace pectus {

/// Moves every point along its normal onto the locally weighted mean surface of the points within
/// radius_mm (Gaussian weights, sigma = radius / 2; neighbours whose normals differ by more than 60
/// degrees, such as the other side of a thin part, are left out). Overlapping sweeps that are not
/// perfectly aligned meet in the middle; detail smaller than the radius is smoothed. Points without a
/// normal (zero row) stay. No-op for radius 0.
/// @param[in]     radius_mm  blending radius (mm), >= 0
/// @param[in,out] cloud      positions and unit normals (#points by 3 each)
void BlendAlongNormals(double radius_mm, PointCloud* cloud);

/// Statistical outlier removal (Rusu et al. 2008): the rows whose mean distance to their k nearest
/// neighbours is at most mean + std_ratio * standard deviation of that distance over the cloud.
/// Every row when k is 0 or the cloud has k + 1 points or fewer.
/// @param[in] points     #points by 3 (mm)
/// @param[in] k          neighbours, >= 0
/// @param[in] std_ratio  > 0
std::vector<std::uint32_t> StatisticalInliers(const Points3& points, int k, double std_ratio);

/// The given rows of a cloud, with all its attributes.
PointCloud SelectRows(const PointCloud& cloud, const std::vector<std::uint32_t>& rows);

}  // namespace pectus
