#include "shape/core/per_vertex_normals.h"

namespace pectus {

Points3 PerVertexNormals(const Points3& V, const Faces3& F, const Eigen::RowVector3d& isolated) {
  Points3 n = Points3::Zero(V.rows(), 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const auto a = F(f, 0), b = F(f, 1), c = F(f, 2);
    // |(b - a) x (c - a)| is twice the face's area: the sum weights each face by its area.
    const Eigen::RowVector3d fn = (V.row(b) - V.row(a)).cross(V.row(c) - V.row(a));
    n.row(a) += fn;
    n.row(b) += fn;
    n.row(c) += fn;
  }
  for (Eigen::Index v = 0; v < n.rows(); ++v) {
    const double length = n.row(v).norm();
    n.row(v) = length > 0.0 ? Eigen::RowVector3d(n.row(v) / length) : isolated;
  }
  return n;
}

}  // namespace pectus
