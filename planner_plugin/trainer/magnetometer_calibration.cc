#include "planner_plugin/trainer/magnetometer_calibration.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <cmath>

#include "shape/core/error.h"

namespace pectus::trainer {

MagnetometerCalibration FitMagnetometerCalibration(const std::vector<Eigen::Vector3d>& readings_uT,
                                                   const std::string& what) {
  const auto n = static_cast<Eigen::Index>(readings_uT.size());
  if (n < 9) ThrowBadInput(what, "an ellipsoid fit needs at least 9 readings, got " + std::to_string(n));
  // Centre and scale the readings first (the algebraic fit is not invariant to them).
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& m : readings_uT) mean += m;
  mean /= static_cast<double>(n);
  double scale = 0;
  for (const Eigen::Vector3d& m : readings_uT) scale += (m - mean).norm();
  scale /= static_cast<double>(n);
  if (!(scale > 0)) ThrowBadInput(what, "the readings are all the same");
  // One row per reading: [x^2 y^2 z^2 2xy 2xz 2yz x y z 1] . (A11 A22 A33 A12 A13 A23 b1 b2 b3 c) = 0.
  Eigen::MatrixXd D(n, 10);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d p = (readings_uT[static_cast<std::size_t>(i)] - mean) / scale;
    D.row(i) << p.x() * p.x(), p.y() * p.y(), p.z() * p.z(), 2 * p.x() * p.y(), 2 * p.x() * p.z(),
        2 * p.y() * p.z(), p.x(), p.y(), p.z(), 1;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(D, Eigen::ComputeFullV);
  const Eigen::Matrix<double, 10, 1> v = svd.matrixV().col(9);
  Eigen::Matrix3d A;
  A << v(0), v(3), v(4), v(3), v(1), v(5), v(4), v(5), v(2);
  Eigen::Vector3d b = v.segment<3>(6);
  double c = v(9);
  if (A.trace() < 0) {  // the quadric's sign: A positive definite for an ellipsoid
    A = -A;
    b = -b;
    c = -c;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(A);
  if (eig.eigenvalues().minCoeff() <= 1e-9 * eig.eigenvalues().maxCoeff() ||
      svd.singularValues()(8) < 1e-6 * svd.singularValues()(0)) {
    ThrowBadInput(what,
                  "the readings do not determine an ellipsoid (too few orientations, or all in a plane)");
  }
  // (p - p0)^T A (p - p0) = k with p0 = -A^-1 b / 2, k = p0^T A p0 - c.
  const Eigen::Vector3d p0 = -0.5 * A.ldlt().solve(b);
  const double k = p0.dot(A * p0) - c;
  if (!(k > 0)) ThrowBadInput(what, "the fitted quadric is not an ellipsoid");
  // W' = sqrt(A / k) maps the scaled readings onto the unit sphere; in uT: W (m - h) with |.| = 1, then
  // rescaled so that the corrected field keeps the readings' mean strength (det W = 1).
  const Eigen::Matrix3d root =
      eig.eigenvectors() * (eig.eigenvalues() / k).cwiseSqrt().asDiagonal() * eig.eigenvectors().transpose();
  MagnetometerCalibration out;
  out.hard_iron_offset = mean + scale * p0;
  out.soft_iron_correction = root / std::cbrt(root.determinant());
  double sum = 0, sum_sq = 0;
  for (const Eigen::Vector3d& m : readings_uT) sum += out.Apply(m).norm();
  out.field_strength = sum / static_cast<double>(n);
  for (const Eigen::Vector3d& m : readings_uT)
    sum_sq += std::pow(out.Apply(m).norm() - out.field_strength, 2);
  out.rms_residual = std::sqrt(sum_sq / static_cast<double>(n));
  return out;
}

}  // namespace pectus::trainer
