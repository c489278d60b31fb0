// pectus: distance maps between two surfaces: nearest-point distance (as the dissertation's colour maps,
// §5.1 Figs. 44 and 46) and signed point-to-surface distance; their statistics.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>

#include "shape/core/geometry.h"

namespace pectus {

/// Which distance a map holds.
enum class DistanceKind {
  kNearestPoint,   ///< |p - q|, q the nearest vertex of the reference (>= 0)
  kSignedSurface,  ///< distance to the nearest point of the reference's triangles, signed: positive on
                   ///< the side its normals point to (outside / anterior), negative behind it
};

/// "nearest" or "signed"; throws Error(kUsage) otherwise.
DistanceKind ParseDistanceKind(const std::string& text);
std::string ToString(DistanceKind kind);

/// Statistics of a distance map (mm). Percentiles are of |d|.
struct DistanceStats {
  Eigen::Index count = 0;
  double min = 0.0, max = 0.0;  ///< signed extremes
  double max_abs = 0.0, mean = 0.0, mean_abs = 0.0, rms = 0.0;
  double p50 = 0.0, p90 = 0.0, p95 = 0.0, p99 = 0.0;
  /// {"count", "min_mm", "max_mm", "max_abs_mm", "mean_mm", "mean_abs_mm", "rms_mm", "p50_abs_mm", ...}
  nlohmann::json ToJson() const;
};

/// Statistics of #n distances (mm); all zero for n = 0.
DistanceStats SummarizeDistances(const Eigen::VectorXd& distances);

/// A distance map: one distance per query point.
struct DistanceMapResult {
  Eigen::VectorXd distances;  ///< #points, mm
  Points3 closest;            ///< #points by 3: the closest reference point of each query point, mm
  DistanceStats stats;
  std::string message;  ///< one line: kind, count, max |d|, RMS
};

/// Distances from each row of `points` (#n by 3, mm) to `reference`. kSignedSurface needs faces (throws
/// Error(kBadInput) naming `what` without them); kNearestPoint uses the vertices only. The closest point
/// on the triangles is exact (every triangle that can hold it is checked); the sign uses angle-weighted
/// pseudo-normals (Baerentzen & Aanaes 2005), so it is right at edges and vertices of a closed or
/// consistently oriented surface.
DistanceMapResult ComputeDistanceMap(const Points3& points, const TriangleMesh& reference,
                                     DistanceKind kind = DistanceKind::kSignedSurface,
                                     const std::string& what = "reference surface");

}  // namespace pectus
