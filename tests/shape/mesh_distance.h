// Test helper: exact distances from points to a triangle mesh (closest point on each nearby triangle).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "registration/kdtree.h"
#include "shape/core/geometry.h"

namespace pectus::testing {

// Closest point of triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5).
inline Eigen::Vector3d ClosestOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                         const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
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
