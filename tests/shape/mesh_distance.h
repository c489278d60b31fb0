// Test helper: exact distances from points to a triangle mesh (closest point on each nearby triangle).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "registration/kdtree.h"
#include "shape/core/closest_point_on_triangle.h"
#include "shape/core/geometry.h"

namespace pectus::testing {

// Closest point of triangle abc to p.
inline Eigen::Vector3d ClosestOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                         const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  return ClosestPointOnTriangle(p, a, b, c);
}

// Distance (mm) from each row of `points` to the triangles of `mesh`; the closest points into `closest`
// (#points by 3) when it is not null.
inline Eigen::VectorXd DistancesToMesh(const Points3& points, const TriangleMesh& mesh,
                                       Points3* closest = nullptr) {
  const Eigen::Index nf = mesh.num_faces();
  Points3 centroids(nf, 3);
  double reach = 0;  // farthest vertex from its triangle's centroid
  auto corner = [&](Eigen::Index f, int k) {
    return Eigen::Vector3d(mesh.vertices.positions.row(mesh.faces(f, k)));
  };
  for (Eigen::Index f = 0; f < nf; ++f) {
    centroids.row(f) = ((corner(f, 0) + corner(f, 1) + corner(f, 2)) / 3.0).transpose();
    for (int k = 0; k < 3; ++k) reach = std::max(reach, (corner(f, k) - centroids.row(f).transpose()).norm());
  }
  const KdTree3 tree(centroids);
  Eigen::VectorXd out(points.rows());
  if (closest) closest->resize(points.rows(), 3);
#pragma omp parallel
  {
    std::vector<std::pair<std::uint32_t, double>> near;
#pragma omp for schedule(dynamic, 256)
    for (Eigen::Index i = 0; i < points.rows(); ++i) {
      const Eigen::Vector3d p = points.row(i).transpose();
      std::uint32_t k;
      double d2;
      tree.Nearest(p, &k, &d2);
      tree.Radius(p, std::sqrt(d2) + reach, &near, false);
      double best = INFINITY;
      Eigen::Vector3d best_point = p;
      for (const auto& [f, unused] : near) {
        const Eigen::Vector3d q = ClosestOnTriangle(p, corner(f, 0), corner(f, 1), corner(f, 2));
        if ((q - p).norm() < best) {
          best = (q - p).norm();
          best_point = q;
        }
      }
      out(i) = best;
      if (closest) closest->row(i) = best_point.transpose();
    }
  }
  return out;
}

}  // namespace pectus::testing
