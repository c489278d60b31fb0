// pectus: the oriented normals a surface reconstruction starts from: the cloud's own, or estimated by PCA
// and oriented toward the scanner or by propagation, with a clear error when none can be had.
#pragma once

#include <optional>
#include <string>

#include "registration/kdtree.h"
#include "shape/core/geometry.h"

namespace pectus {

/// Options of SurfaceNormals.
struct SurfaceNormalOptions {
  int neighbours = 16;     ///< k of the PCA normals, [3, 256]
  bool recompute = false;  ///< estimate normals even if the cloud has them
  /// Orient toward this scanner position (mm) instead of by propagation (Hoppe et al. 1992, Sec. 3.3).
  std::optional<Eigen::Vector3d> viewpoint;

  /// False, with the reason in `why`, if a value is out of range.
  bool IsValid(std::string* why) const;
};

/// Oriented normals and where they came from.
struct SurfaceNormalResult {
  Points3 normals;          ///< #points by 3, unit; a zero row where a point has no usable normal
  std::string source;       ///< "input", "viewpoint" or "propagated"
  Eigen::Index usable = 0;  ///< rows with a unit normal
};

/// The cloud's normals when it has usable ones (more than 90 % of unit length), else PCA normals of the
/// `neighbours` nearest points, oriented. Throws Error(kBadInput) naming `what` when no normals can be
/// had: most sampled neighbourhoods are lines (scan lines farther apart than the neighbourhood reaches) or
/// fewer than half the points get one.
/// @param[in] cloud  positions (mm), optionally normals
/// @param[in] tree   k-d tree over cloud.positions
SurfaceNormalResult SurfaceNormals(const PointCloud& cloud, const KdTree3& tree,
                                   const SurfaceNormalOptions& options, const std::string& what);

}  // namespace pectus
