// pectus: surface normals of a point cloud by local PCA, oriented toward a viewpoint or by propagation.
#pragma once

#include <cstdint>
#include <string>

#include "registration/kdtree.h"
#include "shape/core/geometry.h"
#include "shape/core/timings.h"

namespace pectus {

/// How normals are given a consistent sign.
enum class NormalOrientation {
  kNone,             ///< the sign PCA gives (arbitrary)
  kTowardViewpoint,  ///< n . (viewpoint - p) >= 0, as for one scanner position
  kPropagate,        ///< along a minimum spanning tree of the kNN graph (Hoppe et al. 1992, Sec. 3.3)
};

/// Options of EstimateNormals.
struct NormalOptions {
  int k = 16;                  ///< neighbours per point, the point itself included (>= 3)
  double max_radius_mm = 0.0;  ///< neighbours farther than this are dropped; 0 = no limit
  NormalOrientation orientation = NormalOrientation::kTowardViewpoint;
  Eigen::Vector3d viewpoint = Eigen::Vector3d::Zero();  ///< mm, for kTowardViewpoint
  /// kPropagate: neighbours per point in the orientation graph (<= k). Each connected component of the
  /// graph starts from its point farthest from the cloud's centroid, whose normal is made to point away
  /// from that centroid (outward for a convex object or a chest wall seen from the front).
  int propagation_k = 8;

  /// False, with the reason in `why`, if a value is out of range.
  bool IsValid(std::string* why) const;
};

/// Normals and what they cost.
struct NormalResult {
  Points3 normals;                  ///< #points by 3 unit normals; (0,0,0) where fewer than 3 neighbours
  Eigen::VectorXd curvature;        ///< #points surface variation lambda_min / (sum of lambdas), in [0, 1/3]
  std::int64_t num_degenerate = 0;  ///< points with fewer than 3 neighbours (zero normal)
  std::int64_t num_components = 0;  ///< kPropagate: connected components of the orientation graph
  Timings timings_s;                ///< "normals": wall time (s)
};

/// Normals by principal component analysis of the k nearest neighbours (the eigenvector of the smallest
/// eigenvalue of their covariance, Hoppe et al. 1992, Sec. 3.2), in parallel over points (OpenMP), then
/// oriented as asked. Deterministic: the same input gives the same output for any number of threads.
/// @param[in] points   #points by 3 positions (mm)
/// @param[in] options  neighbourhood and orientation
/// @param[in] tree     a k-d tree over `points`, or nullptr to build one here
/// @return normals (#points by 3) with curvature. Throws Error(kUsage) for invalid options.
NormalResult EstimateNormals(const Points3& points, const NormalOptions& options = {},
                             const KdTree3* tree = nullptr);

}  // namespace pectus
