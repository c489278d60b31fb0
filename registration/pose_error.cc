#include "registration/pose_error.h"

#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "shape/core/error.h"

namespace pectus {

PoseError ComparePoses(const Similarity3& estimate, const Similarity3& truth, const Eigen::Vector3d& at) {
  PoseError e;
  const Eigen::Matrix3d dR = estimate.rotation * truth.rotation.transpose();
  e.rotation_deg = Eigen::AngleAxisd(dR).angle() * 180.0 / 3.14159265358979323846;
  // In doubles: at 1e7 mm from the origin the difference keeps about 1e-9 mm of precision.
  const Eigen::Vector3d ea = estimate.scale * (estimate.rotation * at) + estimate.translation;
  const Eigen::Vector3d ta = truth.scale * (truth.rotation * at) + truth.translation;
  e.translation_mm = (ea - ta).norm();
  e.scale_ratio = estimate.scale / truth.scale;
  return e;
}

double RmsDisplacement(const Points3& points, const Similarity3& a, const Similarity3& b) {
  if (points.rows() == 0) return 0.0;
  const Eigen::Matrix3d A = a.scale * a.rotation, B = b.scale * b.rotation;
  const Eigen::Matrix3d D = A - B;
  const Eigen::Vector3d dt = a.translation - b.translation;
  double sum = 0.0;
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    sum += (D * points.row(i).transpose() + dt).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(points.rows()));
}

Rigid3 BestCommonMotion(const std::vector<PointCloud>& sets, const std::vector<Rigid3>& from,
                        const std::vector<Rigid3>& to, Eigen::Index stride) {
  if (from.size() != sets.size() || to.size() != sets.size() || stride < 1) {
    ThrowUsage("BestCommonMotion: " + std::to_string(sets.size()) + " point sets, " +
               std::to_string(from.size()) + " and " + std::to_string(to.size()) + " poses, stride " +
               std::to_string(stride));
  }
  Eigen::Index n = 0;
  for (const PointCloud& c : sets) n += (c.size() + stride - 1) / stride;
  if (n < 3) ThrowBadInput("BestCommonMotion", "fewer than 3 points in all the sets");
  Eigen::Matrix3Xd A(3, n), B(3, n);
  Eigen::Index k = 0;
  for (std::size_t s = 0; s < sets.size(); ++s) {
    for (Eigen::Index i = 0; i < sets[s].size(); i += stride, ++k) {
      const Eigen::Vector3d x = sets[s].positions.row(i).transpose();
      A.col(k) = from[s] * x;
      B.col(k) = to[s] * x;
    }
  }
  Rigid3 G = Rigid3::Identity();
  G.matrix() = Eigen::umeyama(A, B, /*with_scaling=*/false);
  return G;
}

}  // namespace pectus
