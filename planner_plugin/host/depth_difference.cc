#include "planner_plugin/host/depth_difference.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace pectus::planner {

Eigen::VectorXd DepthDifference(const Points3& points, const Eigen::Vector3d& direction,
                                const TriangleMesh& surface) {
  const double kNaN = std::numeric_limits<double>::quiet_NaN();
  Eigen::VectorXd t = Eigen::VectorXd::Constant(points.rows(), kNaN);
  if (surface.num_faces() == 0 || points.rows() == 0) return t;
  // The plane across the direction: coordinates (u, v); heights h along the direction.
  const Eigen::Vector3d a = direction.normalized();
  const Eigen::Vector3d u = a.unitOrthogonal(), v = a.cross(u);
  const Points3& x = surface.vertices.positions;
  Eigen::MatrixX2d uv(x.rows(), 2);
  Eigen::VectorXd h(x.rows());
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const Eigen::Vector3d p = x.row(i).transpose();
    uv.row(i) << p.dot(u), p.dot(v);
    h(i) = p.dot(a);
  }
  // Bins of about the mean projected triangle size, each listing the triangles whose box overlaps it.
  const Eigen::Vector2d lo = uv.colwise().minCoeff().transpose(), hi = uv.colwise().maxCoeff().transpose();
  const double area = std::max((hi - lo).prod(), 1e-12);
  double cell = std::max(std::sqrt(2.0 * area / static_cast<double>(surface.num_faces())), 1e-6);
  const double limit = 2.0 * static_cast<double>(surface.num_faces()) + 16;  // bins, at most
  while (((hi.x() - lo.x()) / cell + 1) * ((hi.y() - lo.y()) / cell + 1) > limit) cell *= 1.5;
  const int nu = static_cast<int>((hi.x() - lo.x()) / cell) + 1;
  const int nv = static_cast<int>((hi.y() - lo.y()) / cell) + 1;
  const double su = nu / std::max(hi.x() - lo.x(), 1e-12), sv = nv / std::max(hi.y() - lo.y(), 1e-12);
  auto bin_u = [&](double value) { return std::clamp(static_cast<int>((value - lo.x()) * su), 0, nu - 1); };
  auto bin_v = [&](double value) { return std::clamp(static_cast<int>((value - lo.y()) * sv), 0, nv - 1); };
  std::vector<std::vector<std::int32_t>> bins(static_cast<std::size_t>(nu) * nv);
  for (Eigen::Index f = 0; f < surface.num_faces(); ++f) {
    Eigen::Vector2d fmin = uv.row(surface.faces(f, 0)).transpose(), fmax = fmin;
    for (int c = 1; c < 3; ++c) {
      fmin = fmin.cwiseMin(uv.row(surface.faces(f, c)).transpose());
      fmax = fmax.cwiseMax(uv.row(surface.faces(f, c)).transpose());
    }
    for (int i = bin_u(fmin.x()); i <= bin_u(fmax.x()); ++i) {
      for (int j = bin_v(fmin.y()); j <= bin_v(fmax.y()); ++j) {
        bins[static_cast<std::size_t>(i) * nv + j].push_back(static_cast<std::int32_t>(f));
      }
    }
  }
#pragma omp parallel for schedule(static)
  for (Eigen::Index k = 0; k < points.rows(); ++k) {
    const Eigen::Vector3d p = points.row(k).transpose();
    const Eigen::Vector2d q(p.dot(u), p.dot(v));
    if (q.x() < lo.x() || q.x() > hi.x() || q.y() < lo.y() || q.y() > hi.y()) continue;
    double best = kNaN;
    for (std::int32_t f : bins[static_cast<std::size_t>(bin_u(q.x())) * nv + bin_v(q.y())]) {
      const int i0 = surface.faces(f, 0), i1 = surface.faces(f, 1), i2 = surface.faces(f, 2);
      const Eigen::Vector2d a0 = uv.row(i0).transpose(), e1 = uv.row(i1).transpose() - a0,
                            e2 = uv.row(i2).transpose() - a0, d = q - a0;
      const double det = e1.x() * e2.y() - e1.y() * e2.x();
      if (std::abs(det) < 1e-15) continue;  // seen edge-on
      const double l1 = (d.x() * e2.y() - d.y() * e2.x()) / det, l2 = (e1.x() * d.y() - e1.y() * d.x()) / det;
      constexpr double kEps = 1e-9;
      if (l1 < -kEps || l2 < -kEps || l1 + l2 > 1 + kEps) continue;
      const double depth = (1 - l1 - l2) * h(i0) + l1 * h(i1) + l2 * h(i2) - p.dot(a);
      if (std::isnan(best) || std::abs(depth) < std::abs(best)) best = depth;
    }
    t(k) = best;
  }
  return t;
}

}  // namespace pectus::planner
