// pectus planner host: how far a surface lies in front of (or behind) points, along one direction: the
// depth difference between two chests as a surgeon reads it (the anterior direction), fast enough to
// score thousands of candidate plans: the points are binned once across the direction (DepthProbe), and
// each surface then costs one pass over its faces.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "shape/core/geometry.h"

namespace pectus::planner {

/// Fixed points and a direction, binned once, against which many surfaces are measured.
class DepthProbe {
 public:
  /// @param[in] points     #points by 3, mm
  /// @param[in] direction  the direction depths are measured along (normalised here; non-zero)
  DepthProbe(const Points3& points, const Eigen::Vector3d& direction);

  /// For each point p, the t (mm) with p + t * direction on `surface`: positive when the surface lies
  /// ahead of the point along the direction. Where the line meets the surface more than once (a fold),
  /// the smallest |t| (the first face in face order among equals); NaN where it misses the surface.
  /// O(#faces + #points) for a surface that is a height field along the direction.
  Eigen::VectorXd Depth(const TriangleMesh& surface) const;
  /// The same for a surface given as #vertices by 3 positions and #faces by 3 triangles.
  Eigen::VectorXd Depth(const Points3& vertices, const Faces3& faces) const;

  /// Vertices projected on the probe's axes: (u, v) across the direction and h along it. Linear in the
  /// positions (no origin), so the projection of a + F b is that of a plus F times that of b.
  struct Projected {
    Eigen::MatrixX2d uv;  ///< #vertices by 2, mm
    Eigen::VectorXd h;    ///< #vertices, mm
  };
  Projected Project(const Points3& vertices) const;
  /// Depth() of a surface given by its projected vertices.
  Eigen::VectorXd Depth(const Projected& vertices, const Faces3& faces) const;

 private:
  Eigen::Vector3d a_, u_, v_;  // the direction and two axes across it
  Eigen::MatrixX2d q_;         // per point: (u, v)
  Eigen::VectorXd h_;          // per point: height along a_
  // Bins of the points over their (u, v) box: bin (i, j) holds points start_[i nv + j] .. start_[.. + 1]
  // of order_.
  Eigen::Vector2d lo_ = Eigen::Vector2d::Zero(), hi_ = Eigen::Vector2d::Zero(),
                  scale_ = Eigen::Vector2d::Zero();
  int nu_ = 0, nv_ = 0;
  std::vector<std::int32_t> start_, order_;
  std::vector<double> binned_uv_;  // (u, v) of order_[s] at 2 s, 2 s + 1: the bins' points side by side
};

/// DepthProbe(points, direction).Depth(surface): for one surface.
Eigen::VectorXd DepthDifference(const Points3& points, const Eigen::Vector3d& direction,
                                const TriangleMesh& surface);

}  // namespace pectus::planner
