#include "registration/voxel_downsample.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "shape/core/error.h"

namespace pectus {

std::vector<std::uint32_t> VoxelDownsample(const Points3& points, double voxel_size_mm,
                                           const std::vector<std::uint32_t>* subset) {
  if (!(voxel_size_mm > 0.0) || !std::isfinite(voxel_size_mm)) {
    ThrowUsage("voxel size must be a positive number of mm, got " + std::to_string(voxel_size_mm));
  }
  const std::size_t count = subset ? subset->size() : static_cast<std::size_t>(points.rows());
  auto row = [&](std::size_t k) { return subset ? (*subset)[k] : static_cast<std::uint32_t>(k); };
  if (count == 0) return {};

  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (std::size_t k = 0; k < count; ++k) {
    const Eigen::Vector3d p = points.row(row(k)).transpose();
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  constexpr double kMaxCells = 2097151.0;  // 21 bits per axis in a 64-bit key
  if (((hi - lo) / voxel_size_mm).maxCoeff() >= kMaxCells) {
    ThrowUsage("voxel size " + std::to_string(voxel_size_mm) + " mm is too small for an extent of " +
               std::to_string((hi - lo).maxCoeff()) + " mm");
  }

  // Sort (voxel key, row) pairs so that every voxel's points are contiguous; ties keep row order.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(count);
  const double inv = 1.0 / voxel_size_mm;
#pragma omp parallel for schedule(static)
  for (std::int64_t k = 0; k < static_cast<std::int64_t>(count); ++k) {
    const std::uint32_t r = row(static_cast<std::size_t>(k));
    const Eigen::Vector3d c = ((points.row(r).transpose() - lo) * inv).array().floor();
    const std::uint64_t key = (static_cast<std::uint64_t>(c.x()) << 42) |
                              (static_cast<std::uint64_t>(c.y()) << 21) | static_cast<std::uint64_t>(c.z());
    keyed[static_cast<std::size_t>(k)] = {key, r};
  }
  std::sort(keyed.begin(), keyed.end());

  std::vector<std::uint32_t> out;
  for (std::size_t begin = 0; begin < count;) {
    std::size_t end = begin + 1;
    while (end < count && keyed[end].first == keyed[begin].first) ++end;
    if (end - begin == 1) {
      out.push_back(keyed[begin].second);
    } else {
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (std::size_t k = begin; k < end; ++k) mean += points.row(keyed[k].second).transpose();
      mean /= static_cast<double>(end - begin);
      std::size_t best = begin;
      double best_d2 = std::numeric_limits<double>::infinity();
      for (std::size_t k = begin; k < end; ++k) {
        const double d2 = (points.row(keyed[k].second).transpose() - mean).squaredNorm();
        if (d2 < best_d2) {
          best_d2 = d2;
          best = k;
        }
      }
      out.push_back(keyed[best].second);
    }
    begin = end;
  }
  return out;
}

double MedianPointSpacing(const Points3& points, const KdTree3& tree, int samples) {
  return MedianOverPickedRows(points.rows(), samples, [&](Eigen::Index i) {
    std::uint32_t idx[2];
    double d2[2];
    tree.Knn(points.row(i).transpose(), 2, idx, d2);  // two found: there are at least two points
    return std::sqrt(d2[1]);
  });
}

}  // namespace pectus
