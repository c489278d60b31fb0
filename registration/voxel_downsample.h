// pectus: voxel-grid subsampling and point spacing, the sampling steps of coarse-to-fine registration.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "registration/kdtree.h"
#include "shape/core/geometry.h"

namespace pectus {

/// One representative per occupied cube of side `voxel_size_mm`: the point of the cube nearest the mean
/// of the cube's points (an input point, so its normal and attributes stay valid). Deterministic.
/// @param[in] points         #points by 3 positions (mm)
/// @param[in] voxel_size_mm  cube side (mm), > 0
/// @param[in] subset         rows of `points` to consider, or nullptr for all
/// @return rows of `points`, one per occupied voxel, in voxel order. Throws Error(kUsage) for a voxel
///         size that is not positive or so small that the grid would exceed 2^21 cells along an axis.
std::vector<std::uint32_t> VoxelDownsample(const Points3& points, double voxel_size_mm,
                                           const std::vector<std::uint32_t>* subset = nullptr);

/// How many points MedianPointSpacing picks by default.
inline constexpr int kSpacingSamples = 256;

/// The typical distance between neighbouring points (mm): the median distance from up to `samples`
/// evenly picked points to their nearest other point. 0 for fewer than two points.
/// @param[in] points  #points by 3 positions (mm)
/// @param[in] tree    k-d tree over `points`
double MedianPointSpacing(const Points3& points, const KdTree3& tree, int samples = kSpacingSamples);

/// The median of `spacing(i)` over the rows MedianPointSpacing picks: min(n, samples) rows, evenly spread
/// over the n points (the element at index size / 2 once sorted). `spacing` may return +infinity for a
/// row whose distance is only known to exceed every finite one; the result is then +infinity unless more
/// than half are known. 0 for fewer than two points.
template <class Spacing>
double MedianOverPickedRows(Eigen::Index n, int samples, Spacing spacing) {
  if (n < 2 || samples < 1) return 0.0;
  const Eigen::Index m = std::min<Eigen::Index>(n, samples);
  std::vector<double> values;
  values.reserve(static_cast<std::size_t>(m));
  for (Eigen::Index s = 0; s < m; ++s) values.push_back(spacing(s * n / m));
  auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

}  // namespace pectus
