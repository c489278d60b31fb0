// pectus: the point of a triangle nearest to a point (Ericson, Real-Time Collision Detection, §5.1.5):
// Voronoi regions of the vertices, edges and face, no square root.
#pragma once

#include <Eigen/Core>

namespace pectus {

/// The point of triangle (a, b, c) nearest to p (mm, any frame). `feature` (if given): where it lies, 0-2
/// vertex a, b, c; 3-5 edge ab, bc, ca; 6 the face (for pseudo-normals: signed distances). No allocation;
/// never throws.
inline Eigen::Vector3d ClosestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                              const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                              int* feature = nullptr) noexcept {
  int unused = 0;
  int& where = feature != nullptr ? *feature : unused;
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return where = 0, a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return where = 1, b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return where = 3, Eigen::Vector3d(a + ab * (d1 / (d1 - d3)));
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return where = 2, c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return where = 5, Eigen::Vector3d(a + ac * (d2 / (d2 - d6)));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return where = 4, Eigen::Vector3d(b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
  const double denom = 1.0 / (va + vb + vc);
  return where = 6, Eigen::Vector3d(a + ab * (vb * denom) + ac * (vc * denom));
}

}  // namespace pectus
