#include "planner_plugin/host/depth_difference.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pectus::planner {
namespace {

// The bin of coordinate `value` among `count` bins of 1 / `scale` from `lo`, clamped to the first and last
// (before the conversion to int: a far or non-finite coordinate must not overflow it).
int BinOf(double value, double lo, double scale, int count) {
  const double x = (value - lo) * scale;
  if (!(x > 0.0)) return 0;  // also NaN
  if (x >= count - 1) return count - 1;
  return static_cast<int>(x);
}

}  // namespace

DepthProbe::DepthProbe(const Points3& points, const Eigen::Vector3d& direction)
    : a_(direction.normalized()), u_(a_.unitOrthogonal()), v_(a_.cross(u_)) {
  const Eigen::Index n = points.rows();
  q_.resize(n, 2);
  h_.resize(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const Eigen::Vector3d p = points.row(k).transpose();
    q_.row(k) << p.dot(u_), p.dot(v_);
    h_(k) = p.dot(a_);
  }
  if (n == 0) return;
  // Bins of about one point each over the points' box (measured: fewer tests per face than two).
  lo_ = q_.colwise().minCoeff().transpose();
  hi_ = q_.colwise().maxCoeff().transpose();
  const Eigen::Vector2d extent = (hi_ - lo_).cwiseMax(1e-9);
  const double cell = std::max(std::sqrt(1.0 * extent.prod() / static_cast<double>(n)), 1e-6);
  const double most = 2.0 * static_cast<double>(n) + 4.0;  // bins per axis, at most (in double: no overflow)
  nu_ = static_cast<int>(std::min(extent.x() / cell + 1.0, most));
  nv_ = static_cast<int>(std::min(extent.y() / cell + 1.0, most));
  scale_ = Eigen::Vector2d(nu_ / extent.x(), nv_ / extent.y());
  start_.assign(static_cast<std::size_t>(nu_) * nv_ + 1, 0);
  std::vector<std::int32_t> bin(static_cast<std::size_t>(n));
  for (Eigen::Index k = 0; k < n; ++k) {
    const int i = BinOf(q_(k, 0), lo_.x(), scale_.x(), nu_), j = BinOf(q_(k, 1), lo_.y(), scale_.y(), nv_);
    bin[static_cast<std::size_t>(k)] = i * nv_ + j;
    ++start_[static_cast<std::size_t>(i * nv_ + j) + 1];
  }
  for (std::size_t b = 0; b + 1 < start_.size(); ++b) start_[b + 1] += start_[b];
  order_.resize(static_cast<std::size_t>(n));
  std::vector<std::int32_t> fill(start_.begin(), start_.end() - 1);
  for (Eigen::Index k = 0; k < n; ++k) {
    order_[static_cast<std::size_t>(fill[static_cast<std::size_t>(bin[static_cast<std::size_t>(k)])]++)] =
        static_cast<std::int32_t>(k);
  }
  binned_uv_.resize(2 * order_.size());
  for (std::size_t s = 0; s < order_.size(); ++s) {
    binned_uv_[2 * s] = q_(order_[s], 0);
    binned_uv_[2 * s + 1] = q_(order_[s], 1);
  }
}

Eigen::VectorXd DepthProbe::Depth(const TriangleMesh& surface) const {
  return Depth(surface.vertices.positions, surface.faces);
}

Eigen::VectorXd DepthProbe::Depth(const Points3& x, const Faces3& faces) const {
  return Depth(Project(x), faces);
}

DepthProbe::Projected DepthProbe::Project(const Points3& x) const {
  Projected out;
  out.uv.resize(x.rows(), 2);
  out.h.resize(x.rows());
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const Eigen::Vector3d p = x.row(i).transpose();
    out.uv.row(i) << p.dot(u_), p.dot(v_);
    out.h(i) = p.dot(a_);
  }
  return out;
}

Eigen::VectorXd DepthProbe::Depth(const Projected& projected, const Faces3& faces) const {
  const double kNaN = std::numeric_limits<double>::quiet_NaN();
  Eigen::VectorXd t = Eigen::VectorXd::Constant(q_.rows(), kNaN);
  if (faces.rows() == 0 || q_.rows() == 0 || projected.uv.rows() == 0) return t;
  const Eigen::MatrixX2d& uv = projected.uv;
  const Eigen::VectorXd& h = projected.h;
  // Points outside the surface's box across the direction miss it.
  const Eigen::Vector2d box_lo = uv.colwise().minCoeff().transpose(),
                        box_hi = uv.colwise().maxCoeff().transpose();
  auto clamp_u = [&](double value) { return BinOf(value, lo_.x(), scale_.x(), nu_); };
  auto clamp_v = [&](double value) { return BinOf(value, lo_.y(), scale_.y(), nv_); };
  constexpr double kEps = 1e-9;  // barycentric tolerance: a point on an edge belongs to both faces
  // Every face meets the points binned under its box; faces in order, so among equal depths the first
  // face's stays.
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const int i0 = faces(f, 0), i1 = faces(f, 1), i2 = faces(f, 2);
    const Eigen::Vector2d a0 = uv.row(i0).transpose(), a1 = uv.row(i1).transpose(),
                          a2 = uv.row(i2).transpose();
    const Eigen::Vector2d fmin = a0.cwiseMin(a1).cwiseMin(a2), fmax = a0.cwiseMax(a1).cwiseMax(a2);
    if (fmax.x() < lo_.x() || fmin.x() > hi_.x() || fmax.y() < lo_.y() || fmin.y() > hi_.y())
      continue;  // no point
    const Eigen::Vector2d e1 = a1 - a0, e2 = a2 - a0;
    const double det = e1.x() * e2.y() - e1.y() * e2.x();
    if (std::abs(det) < 1e-15) continue;  // seen edge-on
    // A point the barycentric test below accepts (weights >= -kEps) lies within 3 kEps extents of the box.
    const double reach = 3 * kEps * (fmax - fmin).maxCoeff();
    const int u_first = clamp_u(fmin.x()), u_last = clamp_u(fmax.x());
    const int v_first = clamp_v(fmin.y()), v_last = clamp_v(fmax.y());
    for (int i = u_first; i <= u_last; ++i) {
      const auto row = static_cast<std::size_t>(i) * nv_;
      for (std::int32_t s = start_[row + v_first]; s < start_[row + v_last + 1]; ++s) {
        const double qu = binned_uv_[2 * static_cast<std::size_t>(s)],
                     qv = binned_uv_[2 * static_cast<std::size_t>(s) + 1];
        // Within the face's box (widened by the barycentric tolerance's reach) and the surface's.
        if (qu < fmin.x() - reach || qu > fmax.x() + reach || qv < fmin.y() - reach || qv > fmax.y() + reach)
          continue;
        if (qu < box_lo.x() || qu > box_hi.x() || qv < box_lo.y() || qv > box_hi.y()) continue;
        const std::int32_t k = order_[static_cast<std::size_t>(s)];
        const double du = qu - a0.x(), dv = qv - a0.y();
        const double l1 = (du * e2.y() - dv * e2.x()) / det, l2 = (e1.x() * dv - e1.y() * du) / det;
        if (l1 < -kEps || l2 < -kEps || l1 + l2 > 1 + kEps) continue;
        const double depth = (1 - l1 - l2) * h(i0) + l1 * h(i1) + l2 * h(i2) - h_(k);
        if (std::isnan(t(k)) || std::abs(depth) < std::abs(t(k))) t(k) = depth;
      }
    }
  }
  return t;
}

Eigen::VectorXd DepthDifference(const Points3& points, const Eigen::Vector3d& direction,
                                const TriangleMesh& surface) {
  return DepthProbe(points, direction).Depth(surface);
}

}  // namespace pectus::planner
