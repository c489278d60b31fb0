#include "registration/pose_error.h"

#include <cmath>

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

}  // namespace pectus
