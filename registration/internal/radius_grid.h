// pectus: a uniform grid for the k nearest points within a radius no larger than its cell, the search of
// ICP's finer levels (registration/icp.cc). Internal to pectus::registration.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "shape/core/geometry.h"

namespace pectus::icp_detail {

/// The points binned in cubic cells of side `cell()`, each cell's points contiguous (a counting sort).
/// Every point within `cell()` of a query lies in the 3 x 3 x 3 cells around the query's, so a search
/// with a radius up to `cell()` is exact after scanning at most those: the query's own cell first, then
/// the others, each skipped when its box lies beyond the current k-th nearest. On a scanned surface whose
/// spacing is a few times smaller than the cell this costs a fraction of a k-d tree's search (its
/// root-to-leaf descent and backtracking miss the caches), and it gives the same answers: the same points,
/// the same squared distances, nearest first (docs/registration.md, "A grid for the finer levels").
class RadiusGrid {
 public:
  /// Bins `points` in cells of `cell` mm. Empty when `cell` is not positive and finite, when there are no
  /// points, or when the bounding box would need more than `max_cells` cells.
  static std::optional<RadiusGrid> Build(const Points3& points, double cell, std::size_t max_cells);

  double cell() const { return cell_; }
  /// The largest radius a search may use: a cell less a margin for the rounding of the binning.
  double max_radius() const { return cell_ * (1.0 - 1e-9); }

  /// The k <= kMaxK nearest points within `radius` (mm, <= max_radius()) of `query`, closest first: rows into
  /// `indices`, squared distances (mm^2) into `squared_distances`. A point counts when its squared distance
  /// is below radius^2, as in KdTree3::NearestWithin. Returns how many were found.
  static constexpr int kMaxK = 8;
  int NearestWithin(const Eigen::Vector3d& query, double radius, int k, std::uint32_t* indices,
                    double* squared_distances) const;

 private:
  RadiusGrid() = default;
  double cell_ = 0.0, inverse_cell_ = 0.0;
  Eigen::Vector3d low_ = Eigen::Vector3d::Zero();  // the corner of cell (0, 0, 0)
  std::int64_t nx_ = 0, ny_ = 0, nz_ = 0;
  std::vector<std::uint32_t> start_;  // per cell (x-major, z fastest) its first point; one more at the end
  struct Point {
    double x, y, z;
    std::uint32_t row;  // in the input
  };
  std::vector<Point> points_;  // in cell order
};

}  // namespace pectus::icp_detail
