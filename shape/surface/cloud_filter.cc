#include "shape/surface/cloud_filter.h"

#include <cmath>
#include <numeric>

#include "registration/kdtree.h"
#include "shape/core/error.h"

namespace pectus {

void BlendAlongNormals(double radius_mm, PointCloud* cloud) {
  if (!(radius_mm >= 0.0) || !std::isfinite(radius_mm)) ThrowUsage("blending radius must be >= 0 mm");
  if (radius_mm == 0.0 || cloud->empty()) return;
  if (!cloud->has_normals()) ThrowUsage("blending needs normals");
  const KdTree3 tree(cloud->positions);
  const double sigma2 = 0.25 * radius_mm * radius_mm;
  const Points3& positions = cloud->positions;
  const Points3& normals = cloud->normals;
  Points3 moved = positions;
#pragma omp parallel
  {
    std::vector<std::pair<std::uint32_t, double>> neighbours;
#pragma omp for schedule(dynamic, 1024)
    for (Eigen::Index r = 0; r < positions.rows(); ++r) {
      const Eigen::Vector3d p = positions.row(r).transpose();
      const Eigen::Vector3d nr = normals.row(r).transpose();
      if (nr.squaredNorm() < 0.5) continue;
      tree.Radius(p, radius_mm, &neighbours, false);
      double sum_w = 0.0, sum_d = 0.0;
      for (const auto& [k, d2] : neighbours) {
        if (normals.row(k).dot(nr.transpose()) < 0.5) continue;
        const double w = std::exp(-d2 / (2.0 * sigma2));
        sum_w += w;
        sum_d += w * nr.dot(positions.row(k).transpose() - p);
      }
      if (sum_w > 0.0) moved.row(r) = (p + nr * (sum_d / sum_w)).transpose();
    }
  }
  cloud->positions.swap(moved);
}

std::vector<std::uint32_t> StatisticalInliers(const Points3& points, int k, double std_ratio) {
  if (k < 0 || !(std_ratio > 0.0)) ThrowUsage("outlier removal: k >= 0 and ratio > 0 are needed");
  const Eigen::Index n = points.rows();
  std::vector<std::uint32_t> keep;
  if (k == 0 || n <= k + 1) {
    keep.resize(std::size_t(n));
    std::iota(keep.begin(), keep.end(), 0u);
    return keep;
  }
  const KdTree3 tree(points);
  Eigen::VectorXd mean_d(n);
#pragma omp parallel
  {
    std::vector<std::uint32_t> idx(std::size_t(k) + 1);
    std::vector<double> d2(std::size_t(k) + 1);
#pragma omp for schedule(static)
    for (Eigen::Index r = 0; r < n; ++r) {
      const int found = tree.Knn(points.row(r).transpose(), k + 1, idx.data(), d2.data());
      double s = 0.0;
      for (int j = 1; j < found; ++j) s += std::sqrt(d2[std::size_t(j)]);
      mean_d(r) = s / double(std::max(1, found - 1));
    }
  }
  const double mu = mean_d.mean();
  const double sd = std::sqrt((mean_d.array() - mu).square().mean());
  const double limit = mu + std_ratio * sd;
  keep.reserve(std::size_t(n));
  for (Eigen::Index r = 0; r < n; ++r) {
    if (mean_d(r) <= limit) keep.push_back(std::uint32_t(r));
  }
  return keep;
}

PointCloud SelectRows(const PointCloud& cloud, const std::vector<std::uint32_t>& rows) {
  auto take = [&](const auto& m) {
    std::decay_t<decltype(m)> out(Eigen::Index(rows.size()), m.cols());
    for (std::size_t k = 0; k < rows.size(); ++k) out.row(Eigen::Index(k)) = m.row(rows[k]);
    return out;
  };
  PointCloud out;
  out.positions = take(cloud.positions);
  if (cloud.has_normals()) out.normals = take(cloud.normals);
  if (cloud.has_colors()) out.colors = take(cloud.colors);
  for (const auto& [name, v] : cloud.scalars) {
    Eigen::VectorXd selected(Eigen::Index(rows.size()));
    for (std::size_t k = 0; k < rows.size(); ++k) selected(Eigen::Index(k)) = v(rows[k]);
    out.scalars[name] = selected;
  }
  return out;
}

}  // namespace pectus
